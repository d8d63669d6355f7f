#pragma once
// Ctrl-C / SIGTERM during training: the handler only sets a flag; the training loop polls it,
// saves a checkpoint and returns normally.
#include <signal.h>

#include <atomic>

namespace neraf::train {

// Installs SIGINT and SIGTERM handlers for its lifetime (restoring the previous ones after).
// The flag is owned by this object. A second Ctrl-C while the first is being handled goes to the
// handler from before (io/signal_cleanup.h: delete the temporaries being written, terminate);
// checkpoints are written atomically, so that is safe.
// At most one InterruptGuard may exist at a time (std::logic_error otherwise).
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  bool requested() const { return flag_.load(std::memory_order_relaxed); }
  const std::atomic<bool>& flag() const { return flag_; }

 private:
  std::atomic<bool> flag_{false};
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

}  // namespace neraf::train
