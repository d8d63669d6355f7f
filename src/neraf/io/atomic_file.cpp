#include "neraf/io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "neraf/io/signal_cleanup.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::io {
namespace {

fs::path parent_or_dot(const fs::path& p) {
  return p.has_parent_path() ? p.parent_path() : fs::path(".");
}

void create_parent(const fs::path& target, const std::string& what) {
  if (!target.has_parent_path()) return;
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  require(!ec, what + ": cannot create the folder " + target.parent_path().string() + " (" +
                   ec.message() + "); choose a writable output path");
}

const char* kind_of(fs::file_type t) {
  switch (t) {
    case fs::file_type::symlink:
      return "a symbolic link";
    case fs::file_type::fifo:
      return "a FIFO";
    case fs::file_type::block:
    case fs::file_type::character:
      return "a device";
    case fs::file_type::socket:
      return "a socket";
    case fs::file_type::directory:
      return "a folder";
    case fs::file_type::regular:
      return "a file";
    default:
      return "not a regular file";
  }
}

// Everything under `dir` on disk: one syncfs of its file system instead of an fsync per file
// (a dataset folder holds thousands).
void sync_tree(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_CLOEXEC);
  require(fd >= 0, dir + ": cannot open (" + std::strerror(errno) + ")");
  const int rc = ::syncfs(fd);
  const int err = errno;
  ::close(fd);
  require(rc == 0, dir + ": cannot be flushed to disk (" + std::strerror(err) +
                       "); free space or check the disk");
}

}  // namespace

void require_replaceable_file(const std::string& path) {
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(path, ec);
  if (!fs::exists(st) || fs::is_regular_file(st)) return;
  throw Error(path + ": exists and is " + kind_of(st.type()) +
              "; neraf only replaces regular files, so remove it or choose another output path");
}

void require_creatable(const std::string& path) {
  fs::path target = fs::path(path).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();
  for (const fs::path& part : target) {
    // Room for the longest temporary name made from it (".NAME.old.tmp-PID").
    require(part.string().size() + 20 <= NAME_MAX,
            path + ": the name '" + part.string().substr(0, 40) + "...' is longer than the " +
                std::to_string(NAME_MAX - 20) +
                " characters neraf can write; choose a shorter name");
  }
  std::error_code ec;
  fs::path folder = parent_or_dot(target);
  while (!fs::exists(folder, ec) && folder.has_parent_path() && folder != folder.parent_path())
    folder = folder.parent_path();
  require(fs::is_directory(folder, ec),
          path + ": " + folder.string() + " is not a usable folder (" +
              (ec ? ec.message() : std::string("not a folder")) + "); choose another output path");
  const std::string probe = (folder / (".neraf-probe" + temporary_suffix())).string();
  const int fd = ::open(probe.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC, 0644);
  require(fd >= 0, path + ": cannot create files in " + folder.string() + " (" +
                       std::strerror(errno) + "); choose a writable output path");
  ::close(fd);
  ::unlink(probe.c_str());
}

std::string with_user_path(std::string message, const std::string& tmp, const std::string& path) {
  for (size_t at; (at = message.find(tmp)) != std::string::npos;)
    message.replace(at, tmp.size(), path);
  if (message.find(std::strerror(ENOSPC)) != std::string::npos &&
      message.find("free") == std::string::npos)
    message += "; free disk space and retry";
  return message;
}

void sync_path(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  require(fd >= 0, path + ": cannot open for flushing (" + std::strerror(errno) + ")");
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  // EINVAL: the file system does not support fsync (nothing to make durable there).
  require(rc == 0 || err == EINVAL, path + ": cannot be flushed to disk (" + std::strerror(err) +
                                        "); free space or check the disk");
}

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  const fs::path target(path);
  create_parent(target, path);
  require_replaceable_file(path);
  const std::string tmp = path + temporary_suffix();
  const RemoveOnSignal remove_on_ctrl_c(tmp);
  std::error_code ec;
  try {
    write(tmp);
    sync_path(tmp);
  } catch (const Interrupted&) {
    fs::remove(tmp, ec);
    throw;
  } catch (const std::runtime_error& e) {
    fs::remove(tmp, ec);
    throw Error(with_user_path(e.what(), tmp, path));
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(path + ": cannot write the file (" + ec.message() +
                "); choose a writable output path");
  }
  sync_path(parent_or_dot(target).string());
}

void write_text_atomically(const std::string& path, const std::string& text) {
  write_atomically(path, [&](const std::string& tmp) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    require(fd >= 0, path + ": cannot open for writing (" + std::strerror(errno) +
                         "); choose a writable output path");
    size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const int err = n < 0 ? errno : ENOSPC;
        ::close(fd);
        throw Error(path + ": write failed (" + std::strerror(err) + "); free space and retry");
      }
      done += static_cast<size_t>(n);
    }
    require(::close(fd) == 0,
            path + ": write failed (" + std::strerror(errno) + "); free space and retry");
  });
}

void write_folder_atomically(const std::string& dir,
                             const std::function<void(const std::string&)>& write,
                             FolderWrite mode) {
  fs::path target = fs::path(dir).lexically_normal();
  if (target.filename().empty()) target = target.parent_path();  // "out/" → "out"
  create_parent(target, dir);
  const fs::path parent = parent_or_dot(target);
  remove_stale_temporaries(parent.string());
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(target, ec);
  const bool exists = fs::exists(st);
  if (exists) {
    require(fs::is_directory(st), dir + ": exists and is " + std::string(kind_of(st.type())) +
                                      ", not a folder; remove it or choose another output folder");
    require(mode != FolderWrite::create || fs::is_empty(target, ec),
            dir + ": folder exists and is not empty; choose a new output folder");
  }
  const std::string name = target.filename().string();
  const fs::path tmp = parent / ("." + name + temporary_suffix());
  fs::remove_all(tmp, ec);
  fs::create_directory(tmp, ec);
  require(!ec, dir + ": cannot create a temporary folder beside it (" + ec.message() +
                   "); choose a writable output folder");
  const RemoveOnSignal remove_on_ctrl_c(tmp.string());
  try {
    write(tmp.string());
    sync_tree(tmp.string());
  } catch (const Interrupted&) {
    fs::remove_all(tmp, ec);
    throw;
  } catch (const std::runtime_error& e) {
    fs::remove_all(tmp, ec);
    throw Error(with_user_path(e.what(), tmp.string(), target.string()));
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
  if (exists && mode == FolderWrite::merge) {
    for (const auto& entry : fs::directory_iterator(tmp, ec)) {
      const fs::path to = target / entry.path().filename();
      require_replaceable_file(to.string());
      fs::rename(entry.path(), to, ec);
      if (ec) {
        const std::string why = ec.message();
        fs::remove_all(tmp, ec);
        throw Error(to.string() + ": cannot move the finished file into place (" + why + ")");
      }
    }
    fs::remove_all(tmp, ec);
    sync_path(target.string());
    return;
  }
  // The old folder is moved aside, not deleted, until the new one is in place.
  const fs::path old = parent / ("." + name + ".old" + temporary_suffix());
  if (exists) {
    fs::rename(target, old, ec);
    if (ec) {
      fs::remove_all(tmp, ec);
      throw Error(dir + ": cannot replace the folder (" + ec.message() + ")");
    }
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    const std::string why = ec.message();
    if (exists) fs::rename(old, target, ec);
    fs::remove_all(tmp, ec);
    throw Error(dir + ": cannot move the finished folder into place (" + why + ")");
  }
  sync_path(parent.string());
  if (exists) fs::remove_all(old, ec);
}

std::string temporary_suffix() {
  return ".neraf.tmp-" + std::to_string(static_cast<long long>(::getpid()));
}

int remove_stale_temporaries(const std::string& folder) {
  // Only names neraf makes: "<name>.neraf.tmp-<pid>", and the runtime's mkstemp file inside an
  // export ("...neraf.tmp-<pid>.tmp-XXXXXX"). A user's "take.tmp-2024.wav" is no temporary.
  static const std::regex kTemporary(R"(\.neraf\.tmp-([0-9]{1,9})(\.tmp-[A-Za-z0-9]{6})?$)");
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return 0;
  int removed = 0;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    std::smatch m;
    if (!std::regex_search(name, m, kTemporary)) continue;
    const pid_t pid = static_cast<pid_t>(std::stol(m[1].str()));
    if (pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH)
      continue;  // alive (or not ours to judge)
    std::error_code rm;
    if (fs::remove_all(entry.path(), rm) > 0 && !rm) ++removed;
  }
  return removed;
}

std::string read_text_file(const std::string& path) {
  std::error_code ec;
  require(fs::exists(path, ec), path + ": no such file; check the path");
  require(!fs::is_directory(path, ec), path + ": is a folder, expected a file");
  // A FIFO or device would block the read (or never end).
  require(fs::is_regular_file(path, ec), path + ": is not a regular file; expected a file");
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path + ": cannot open (" + std::strerror(errno) + "); check its permissions");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace neraf::io
