#include "neraf/io/signal_cleanup.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>

namespace neraf::io {
namespace {

constexpr int kSlots = 32;
constexpr size_t kMaxPath = 4096;

enum SlotState : int { kFree = 0, kWriting = 1, kReady = 2 };

// The registry is process-wide static storage because a POSIX signal handler takes no argument;
// slots are claimed and released with lock-free atomics, which a handler may read.
struct Slot {
  std::atomic<int> state{kFree};
  char path[kMaxPath];
};
std::array<Slot, kSlots> g_slots;

// The kernel's record for getdents64 (glibc's readdir is not async-signal-safe).
struct LinuxDirent64 {
  uint64_t d_ino;
  int64_t d_off;
  unsigned short d_reclen;
  unsigned char d_type;
  char d_name[1];
};

// Deletes `name` under the folder `dir_fd`, recursing into folders, with async-signal-safe calls
// only. Symbolic links are removed, never followed.
void remove_tree(int dir_fd, const char* name, int depth) {
  if (::unlinkat(dir_fd, name, 0) == 0 || errno == ENOENT) return;
  if (depth > 32) return;
  const int fd = ::openat(dir_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return;
  alignas(8) char buffer[4096];
  // Deleting while reading a folder may skip entries, so read it again until it is empty.
  for (bool removed = true; removed;) {
    removed = false;
    ::lseek(fd, 0, SEEK_SET);
    for (;;) {
      const long n = ::syscall(SYS_getdents64, fd, buffer, sizeof buffer);
      if (n <= 0) break;
      for (long offset = 0; offset < n;) {
        const auto* entry = reinterpret_cast<const LinuxDirent64*>(buffer + offset);
        offset += entry->d_reclen;
        if (std::strcmp(entry->d_name, ".") == 0 || std::strcmp(entry->d_name, "..") == 0) continue;
        remove_tree(fd, entry->d_name, depth + 1);
        removed = true;
      }
    }
  }
  ::close(fd);
  ::unlinkat(dir_fd, name, AT_REMOVEDIR);
}

extern "C" void remove_registered_and_end(int sig) {
  const int saved_errno = errno;
  for (Slot& slot : g_slots)
    if (slot.state.load() == kReady) remove_tree(AT_FDCWD, slot.path, 0);
  errno = saved_errno;
  // End the process as the signal would have (exit status 128 + sig in a shell).
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace

void install_signal_cleanup() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction current {};
    ::sigaction(sig, nullptr, &current);
    if (current.sa_handler == SIG_IGN) continue;
    struct sigaction sa {};
    sa.sa_handler = remove_registered_and_end;
    sigfillset(&sa.sa_mask);  // one cleanup at a time, not interrupted by another signal
    sa.sa_flags = SA_RESETHAND;
    ::sigaction(sig, &sa, nullptr);
  }
}

RemoveOnSignal::RemoveOnSignal(const std::string& path) {
  if (path.empty() || path.size() >= kMaxPath) return;
  for (int i = 0; i < kSlots; ++i) {
    int expected = kFree;
    if (!g_slots[i].state.compare_exchange_strong(expected, kWriting)) continue;
    std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
    g_slots[i].state.store(kReady);
    slot_ = i;
    return;
  }
}

RemoveOnSignal::~RemoveOnSignal() {
  if (slot_ >= 0) g_slots[slot_].state.store(kFree);
}

}  // namespace neraf::io
