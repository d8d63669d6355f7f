#pragma once
// Durable, atomic output. Every file neraf writes goes to "<path>.tmp-<pid>" in the target's
// folder first; once complete it is fsync'ed, renamed over <path>, and the folder is fsync'ed,
// so neither an interrupted run nor a power cut leaves a half-written output behind. Outputs made
// of several files are built in a temporary folder and renamed into place the same way.
// Only regular files (and, for folders, folders) are ever replaced: a symlink, FIFO or device
// node at the output path is an error, never swapped for a file.
#include <functional>
#include <string>

namespace neraf::io {

// Calls write(tmp_path) and renames tmp_path to path. The parent folder is created if missing.
// If `write` throws, the temporary file is removed and the exception propagates.
void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write);

// Writes `text` (any bytes) to `path` atomically; a short write (disk full) is a neraf::Error.
void write_text_atomically(const std::string& path, const std::string& text);

// What write_folder_atomically does with an existing folder.
enum class FolderWrite {
  create,   // an error unless it is empty
  replace,  // swapped out, and deleted only once the new folder is in place
  merge,    // each new file is renamed over its namesake; other files stay
};

// Builds the folder `dir` through write(tmp_dir) in a temporary folder beside it, fsyncs what
// was written and renames it into place (or, for merge, renames its files into `dir`). If
// `write` throws, the temporary folder is removed, `dir` is as it was, and the exception
// propagates.
void write_folder_atomically(const std::string& dir,
                             const std::function<void(const std::string&)>& write,
                             FolderWrite mode = FolderWrite::create);

// An error raised while writing the temporary `tmp`, told about the user's `path` instead (the
// hidden temporary is gone by the time it is read), with advice when the disk is full.
std::string with_user_path(std::string message, const std::string& tmp, const std::string& path);

// neraf::Error unless `path` is absent or a regular file (what write_atomically may replace).
void require_replaceable_file(const std::string& path);

// Before any work: neraf::Error unless `path` (a file or a folder) could be written there: its
// name and temporary name fit the file system's limit, and the nearest folder that exists on the
// way to it takes a new file (so /proc, a read-only disk or a deleted working folder fail now,
// not after an hour's work). Creates and deletes a probe file; creates nothing else.
void require_creatable(const std::string& path);

// What neraf appends to the name of a file or folder it is writing: ".neraf.tmp-<pid>" (marked as
// neraf's own, so remove_stale_temporaries never takes a user's file for one).
std::string temporary_suffix();

// Removes the temporary files and folders ("*.neraf.tmp-<pid>") that processes which no longer
// exist left in `folder` (a SIGKILL during a write); returns how many. Entries of live processes
// stay.
int remove_stale_temporaries(const std::string& folder);

// fsync of a file or folder (durability of its contents or of its entries); neraf::Error on
// failure.
void sync_path(const std::string& path);

// Reads a whole file; throws neraf::Error naming the file when it is missing or unreadable.
std::string read_text_file(const std::string& path);

}  // namespace neraf::io
