#include "neraf/train/interrupt.h"

#include <stdexcept>

namespace neraf::train {

namespace {
// The one unavoidable static: a POSIX signal handler takes no user argument, so it can only reach
// the active guard's flag through a process-wide pointer. It is set and cleared by the guard's
// constructor/destructor only; lock-free atomics are async-signal-safe.
std::atomic<std::atomic<bool>*> g_active_flag{nullptr};
// The handlers the guard replaced, written before its own is installed.
struct sigaction g_previous_int {};
struct sigaction g_previous_term {};

extern "C" void on_interrupt(int sig) {
  std::atomic<bool>* flag = g_active_flag.load();
  if (flag) flag->store(true);
  // The next signal of this kind goes to the handler from before (io/signal_cleanup.h: delete
  // the temporaries being written, then end the process).
  sigaction(sig, sig == SIGINT ? &g_previous_int : &g_previous_term, nullptr);
}
}  // namespace

InterruptGuard::InterruptGuard() {
  std::atomic<bool>* expected = nullptr;
  if (!g_active_flag.compare_exchange_strong(expected, &flag_))
    throw std::logic_error("InterruptGuard: only one may be active at a time");
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGINT, nullptr, &g_previous_int);
  sigaction(SIGTERM, nullptr, &g_previous_term);
  sigaction(SIGINT, &sa, &old_int_);
  sigaction(SIGTERM, &sa, &old_term_);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
  g_active_flag.store(nullptr);
}

}  // namespace neraf::train
