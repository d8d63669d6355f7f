#include "neraf/runtime/helper_thread.h"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define NERAF_RT_PAUSE() _mm_pause()
#else
#define NERAF_RT_PAUSE() std::this_thread::yield()
#endif

namespace neraf::rt {
namespace {
// ~50 µs of pause instructions (~30-140 cycles each) before falling back to sleeping.
constexpr int kSpins = 1000;

template <typename Pred>
bool spin_until(const Pred& done) {
  for (int i = 0; i < kSpins; ++i) {
    if (done()) return true;
    NERAF_RT_PAUSE();
  }
  return done();
}
}  // namespace

HelperThread::HelperThread() : thread_([this] { loop(); }) {}

HelperThread::~HelperThread() {
  wait();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.store(kStop);
  }
  wake_.notify_one();
  thread_.join();
}

void HelperThread::start(void (*fn)(void*), void* arg) {
  fn_ = fn;  // published by the state change below (release)
  arg_ = arg;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_.store(kPending, std::memory_order_release);
  }
  wake_.notify_one();
}

void HelperThread::wait() {
  auto finished = [this] { return state_.load(std::memory_order_acquire) != kPending; };
  if (spin_until(finished)) return;
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, finished);
}

void HelperThread::loop() {
  auto has_work = [this] { return state_.load(std::memory_order_acquire) != kIdle; };
  for (;;) {
    if (!spin_until(has_work)) {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, has_work);
    }
    if (state_.load(std::memory_order_acquire) == kStop) return;
    fn_(arg_);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      state_.store(kIdle, std::memory_order_release);
    }
    done_.notify_all();
  }
}

}  // namespace neraf::rt
