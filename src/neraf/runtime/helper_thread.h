#pragma once
// One thread that runs a job on request, owned by a Workspace: the channels of one RIR are
// independent (head, calibration, Griffin-Lim), so a binaural query runs channel 1 here while the
// caller runs channel 0, and large trunk layers split their columns the same way. Started once,
// at workspace creation, so that queries create no thread and allocate nothing.
//
// A query hands out several short jobs (one per large layer, then the channels), so both sides
// spin briefly before sleeping: waking a sleeping thread costs ~10-50 µs, a job ~50 µs-3 ms.
// The spins are bounded (~50 µs), so an idle workspace sleeps.
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace neraf::rt {

class HelperThread {
 public:
  HelperThread();   // starts the thread (throws std::system_error if it cannot)
  ~HelperThread();  // waits for a running job, then stops and joins
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  // Runs fn(arg) on the thread; one job at a time: call wait() before the next start().
  void start(void (*fn)(void*), void* arg);
  void wait();  // until the started job has returned (its writes are then visible)

 private:
  enum State : int { kIdle, kPending, kStop };
  void loop();

  std::atomic<int> state_{kIdle};
  void (*fn_)(void*) = nullptr;
  void* arg_ = nullptr;
  std::mutex mutex_;  // with the two condition variables: the sleeping paths
  std::condition_variable wake_, done_;
  std::thread thread_;  // last: starts after the members it uses exist
};

}  // namespace neraf::rt
