#pragma once
// Atomic output: every file neraf writes goes to "<path>.tmp-<pid>" first and is renamed over
// <path> only when complete, so an interrupted run never leaves a half-written output behind.
#include <functional>
#include <string>

namespace neraf::io {

// Calls write(tmp_path) and renames tmp_path to path. The parent folder is created if missing.
// If `write` throws, the temporary file is removed and the exception propagates.
void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write);

// Writes `text` to `path` atomically.
void write_text_atomically(const std::string& path, const std::string& text);

// Reads a whole file; throws neraf::Error naming the file when it is missing or unreadable.
std::string read_text_file(const std::string& path);

}  // namespace neraf::io
