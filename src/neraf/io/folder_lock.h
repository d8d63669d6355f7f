#pragma once
// An exclusive lock on a folder that one process writes (a run folder): flock() on
// FOLDER/.lock, which holds the owner's PID. The kernel drops the lock when the process ends,
// however it ends, so a killed run never leaves its folder locked.
#include <string>

namespace neraf::io {

class FolderLock {
 public:
  // Creates `folder` if needed and locks it; neraf::Error naming the folder and the PID of the
  // process that holds it when another one does.
  explicit FolderLock(const std::string& folder);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  static constexpr const char* kFileName = ".lock";

 private:
  int fd_ = -1;
};

}  // namespace neraf::io
