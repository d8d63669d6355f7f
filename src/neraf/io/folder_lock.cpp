#include "neraf/io/folder_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>

#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::io {

FolderLock::FolderLock(const std::string& folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  require(!ec, folder + ": cannot create the folder (" + ec.message() +
                   "); choose a writable output folder");
  const std::string path = (fs::path(folder) / kFileName).string();
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  require(fd_ >= 0, path + ": cannot open the lock file (" + std::strerror(errno) +
                        "); choose a writable output folder");
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char pid[32] = {0};
    const ssize_t n = ::pread(fd_, pid, sizeof pid - 1, 0);
    ::close(fd_);
    fd_ = -1;
    if (err != EWOULDBLOCK)
      throw Error(path + ": cannot lock (" + std::strerror(err) + ")");
    const std::string holder = n > 0 ? std::string(pid, static_cast<size_t>(n)) : "?";
    throw Error(folder + ": another neraf process (PID " + holder.substr(0, holder.find('\n')) +
                ") is writing this folder; wait for it to finish or choose another output folder");
  }
  const std::string me = std::to_string(static_cast<long long>(::getpid())) + "\n";
  // The PID only serves a second writer's message; the lock holds either way.
  [[maybe_unused]] const bool recorded =
      ::ftruncate(fd_, 0) == 0 &&
      ::pwrite(fd_, me.data(), me.size(), 0) == static_cast<ssize_t>(me.size());
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace neraf::io
