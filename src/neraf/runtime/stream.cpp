// The neraf_stream_* functions of neraf_rt.h: a PartitionedConvolver fed by a worker thread.
//
// Threads:
//   control (the caller of create / set_pose / set_rir / wait / free): validates, then posts a
//     request into the mailbox (a mutex and condition variables: fine here, never on the audio
//     thread). Latest wins: a request the worker has not started yet is replaced by a newer one.
//   worker (one std::thread per stream): takes the request, computes the RIR (neraf_query_rir on
//     its own workspace, for a pose; a copy made by set_rir, for a RIR), transforms it into the
//     convolver's free slot and publishes it (lock-free, SlotExchange), then marks the request
//     completed for neraf_stream_wait.
//   audio (the caller of neraf_stream_process): only PartitionedConvolver::process, which picks
//     the newest published RIR up at the start of a block, wait-free.
// set_rir goes through the worker too, so that one thread only ever fills slots (the slot
// exchange has a single producer) and set_rir never waits behind a pose query in progress.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "neraf/neraf_rt.h"
#include "neraf/runtime/partitioned_convolver.h"
#include "neraf/runtime/status.h"

namespace {

using neraf::rt::fail;
using neraf::rt::PartitionedConvolver;

// 60 s at 192 kHz: a longer max_rir_length is a unit mistake, not a room.
constexpr size_t kMaxRirLength = size_t(60) * 192000;

enum class Request { none, pose, rir };

std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
std::string format(const char* fmt, ...) {
  char buf[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, args);
  va_end(args);
  return buf;
}

}  // namespace

struct neraf_stream {
  // Fixed at creation.
  const neraf_model* model = nullptr;
  neraf_model_info info{};                // the model's (zeros without a model)
  neraf_workspace* workspace = nullptr;   // the worker's, for neraf_query_rir
  int channels = 0;
  size_t max_rir_length = 0;
  size_t query_length = 0;                // samples per channel neraf_query_rir writes
  std::unique_ptr<PartitionedConvolver> convolver;

  // The mailbox between the control thread and the worker, under `mutex`.
  std::mutex mutex;
  std::condition_variable wake;  // to the worker: a request, or stop
  std::condition_variable done;  // to neraf_stream_wait: a request completed
  Request pending = Request::none;
  neraf_pose pose{};               // of a pending pose request
  unsigned flags = 0;
  std::vector<float> pending_rir;  // [channels, pending_length] of a pending set_rir
  size_t pending_length = 0;
  uint64_t requested = 0;          // id of the latest request (the first is 1)
  uint64_t completed = 0;          // id of the latest request the worker finished
  neraf_status completed_status = NERAF_OK;  // and how; its message when not NERAF_OK
  std::string completed_message;
  bool stop = false;

  // The worker's: [channels, max(query_length, max_rir_length)], swapped with pending_rir.
  std::vector<float> work_rir;
  std::thread worker;

  ~neraf_stream() {
    if (worker.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        stop = true;
      }
      wake.notify_all();
      worker.join();  // after the request in progress, if any (a pending one is dropped)
    }
    if (workspace) neraf_workspace_free(workspace);
  }
};

namespace {

// One request, on the worker: the RIR into work_rir, then into a slot, published.
neraf_status serve(neraf_stream* s, Request request, const neraf_pose& pose, unsigned flags,
                   size_t length, std::string& message) {
  size_t stride = length;  // set_rir's copy is planar [channels, length]
  if (request == Request::pose) {
    const neraf_status status = neraf_query_rir(s->model, s->workspace, &pose, flags,
                                                s->work_rir.data(), s->work_rir.size());
    if (status != NERAF_OK) {
      message = std::string("the RIR of the latest pose could not be computed: ") +
                neraf_last_error();  // the worker's own per-thread message
      return status;
    }
    // Planar [channels, query_length]; a max_rir_length below it truncates the RIR.
    stride = s->query_length;
    length = std::min(s->query_length, s->max_rir_length);
  }
  s->convolver->set_rir(s->work_rir.data(), length, stride);
  return NERAF_OK;
}

void run_worker(neraf_stream* s) {
  std::unique_lock<std::mutex> lock(s->mutex);
  for (;;) {
    s->wake.wait(lock, [s] { return s->stop || s->pending != Request::none; });
    if (s->stop) return;
    const Request request = s->pending;
    s->pending = Request::none;
    const uint64_t id = s->requested;
    const neraf_pose pose = s->pose;
    const unsigned flags = s->flags;
    const size_t length = s->pending_length;
    if (request == Request::rir) s->pending_rir.swap(s->work_rir);  // same sizes: no allocation
    lock.unlock();

    neraf_status status;
    std::string message;
    try {
      status = serve(s, request, pose, flags, length, message);
    } catch (const std::bad_alloc&) {
      status = NERAF_ERR_OUT_OF_MEMORY;
      message = "out of memory while computing the RIR of the latest request";
    } catch (...) {
      status = NERAF_ERR_INTERNAL;
      message = "unexpected error while computing the RIR of the latest request";
    }

    lock.lock();
    s->completed = id;
    s->completed_status = status;
    s->completed_message = std::move(message);
    s->done.notify_all();
  }
}

// Posts a request (the pose or the RIR already stored by the caller, under the lock).
void post(neraf_stream* s, std::unique_lock<std::mutex>& lock, Request request) {
  s->pending = request;
  ++s->requested;
  lock.unlock();
  s->wake.notify_one();
}

neraf_status create(const neraf_model* model, int channels, int block_size,
                    size_t max_rir_length, neraf_stream** out) {
  constexpr int kMinBlock = PartitionedConvolver::kMinBlock;
  constexpr int kMaxBlock = PartitionedConvolver::kMaxBlock;
  constexpr int kMaxChannels = PartitionedConvolver::kMaxChannels;
  if (!out) return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_stream_create: out is NULL");
  *out = nullptr;
  if (block_size < kMinBlock || block_size > kMaxBlock)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                format("neraf_stream_create: block_size %d is outside [%d, %d] samples",
                       block_size, kMinBlock, kMaxBlock));
  neraf_model_info info{};
  if (model) {
    const neraf_status status = neraf_model_get_info(model, &info);
    if (status != NERAF_OK) return status;
    if (channels == 0) {
      channels = info.channels;
    } else if (channels != info.channels) {
      return fail(NERAF_ERR_INVALID_ARGUMENT,
                  format("neraf_stream_create: channels %d differs from the model's %d (pass 0 "
                         "for the model's)",
                         channels, info.channels));
    }
    if (max_rir_length == 0) max_rir_length = size_t(std::max(info.rir_length, 0));
  }
  if (channels < 1 || channels > kMaxChannels)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                format("neraf_stream_create: channels %d is outside [1, %d]%s", channels,
                       kMaxChannels, model ? "" : " (without a model, channels must be given)"));
  if (max_rir_length == 0)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                model ? "neraf_stream_create: max_rir_length is 0 and so is the model's rir_length"
                      : "neraf_stream_create: max_rir_length is 0 (without a model it must be "
                        "given, in samples per channel)");
  if (max_rir_length > kMaxRirLength)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                format("neraf_stream_create: max_rir_length %zu exceeds %zu samples (60 s at "
                       "192 kHz)",
                       max_rir_length, kMaxRirLength));

  try {
    auto s = std::make_unique<neraf_stream>();
    s->model = model;
    s->info = info;
    s->channels = channels;
    s->max_rir_length = max_rir_length;
    s->query_length = model ? size_t(info.rir_length) : 0;
    s->convolver = std::make_unique<PartitionedConvolver>(channels, block_size, max_rir_length);
    const size_t rir_floats = size_t(channels) * std::max(s->query_length, max_rir_length);
    s->work_rir.assign(rir_floats, 0.0f);
    s->pending_rir.assign(rir_floats, 0.0f);
    if (model) {
      neraf_status status = neraf_workspace_create(model, &s->workspace);
      // One thread for the worker's queries: Griffin-Lim's helper threads would compete with the
      // audio thread for the cores (a slower pose update is better than a missed block).
      if (status == NERAF_OK) status = neraf_workspace_set_threads(s->workspace, 1);
      if (status != NERAF_OK) return status;
    }
    s->worker = std::thread(run_worker, s.get());
    *out = s.release();
    return NERAF_OK;
  } catch (const std::bad_alloc&) {
    const double mb =
        double(PartitionedConvolver::slot_bytes(channels, block_size, max_rir_length)) / 1e6;
    return fail(NERAF_ERR_OUT_OF_MEMORY,
                format("neraf_stream_create: out of memory (%d channels, block_size %d, "
                       "max_rir_length %zu: the RIR slots alone take %.1f MB)",
                       channels, block_size, max_rir_length, mb));
  } catch (const std::system_error& e) {
    return fail(NERAF_ERR_INTERNAL,
                std::string("neraf_stream_create: cannot start the worker thread: ") + e.what());
  }
}

neraf_status set_pose(neraf_stream* s, const neraf_pose* pose, unsigned flags) {
  if (!s) return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_stream_set_pose: stream is NULL");
  if (!pose) return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_stream_set_pose: pose is NULL");
  if (!s->model)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                "neraf_stream_set_pose: the stream has no model (created with model NULL); "
                "give it RIRs with neraf_stream_set_rir");
  const neraf_status status = neraf::rt::validate_pose(s->info, *pose, flags);
  if (status != NERAF_OK) return status;
  std::unique_lock<std::mutex> lock(s->mutex);
  s->pose = *pose;
  s->flags = flags;
  post(s, lock, Request::pose);
  return NERAF_OK;
}

neraf_status set_rir(neraf_stream* s, const float* rir, int channels, size_t length) {
  if (!s) return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_stream_set_rir: stream is NULL");
  if (!rir) return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_stream_set_rir: rir is NULL");
  if (channels != s->channels)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                format("neraf_stream_set_rir: channels %d differs from the stream's %d", channels,
                       s->channels));
  if (length == 0) return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_stream_set_rir: length is 0");
  if (length > s->max_rir_length)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                format("neraf_stream_set_rir: length %zu exceeds the stream's max_rir_length %zu",
                       length, s->max_rir_length));
  // A NaN would reach every output sample for as long as the RIR is in use.
  const size_t n = size_t(channels) * length;
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(rir[i]))
      return fail(NERAF_ERR_NOT_FINITE,
                  format("neraf_stream_set_rir: rir[%zu][%zu] is NaN or infinite", i / length,
                         i % length));
  std::unique_lock<std::mutex> lock(s->mutex);
  std::memcpy(s->pending_rir.data(), rir, n * sizeof(float));  // the caller may reuse rir now
  s->pending_length = length;
  post(s, lock, Request::rir);
  return NERAF_OK;
}

neraf_status wait(neraf_stream* s, int timeout_ms) {
  if (!s) return fail(NERAF_ERR_INVALID_ARGUMENT, "neraf_stream_wait: stream is NULL");
  if (timeout_ms < 0)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                format("neraf_stream_wait: timeout_ms %d is negative", timeout_ms));
  std::unique_lock<std::mutex> lock(s->mutex);
  const uint64_t target = s->requested;
  if (!s->done.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                        [&] { return s->completed >= target; }))
    return fail(NERAF_ERR_INTERNAL,
                format("neraf_stream_wait: the RIR of the latest request is not ready after %d ms",
                       timeout_ms));
  if (s->completed_status != NERAF_OK) return fail(s->completed_status, s->completed_message);
  return NERAF_OK;
}

}  // namespace

// The C boundary: nothing escapes as an exception.

extern "C" NERAF_RT_API neraf_status neraf_stream_create(const neraf_model* model, int channels,
                                                         int block_size, size_t max_rir_length,
                                                         neraf_stream** out) {
  try {
    return create(model, channels, block_size, max_rir_length, out);
  } catch (const std::bad_alloc&) {
    return fail(NERAF_ERR_OUT_OF_MEMORY, "neraf_stream_create: out of memory");
  } catch (...) {
    return fail(NERAF_ERR_INTERNAL, "neraf_stream_create: unexpected error");
  }
}

extern "C" NERAF_RT_API void neraf_stream_free(neraf_stream* stream) {
  try {
    delete stream;
  } catch (...) {  // join cannot fail here (the worker is not this thread): nothing to report
  }
}

extern "C" NERAF_RT_API neraf_status neraf_stream_set_pose(neraf_stream* stream,
                                                           const neraf_pose* pose,
                                                           unsigned flags) {
  try {
    return set_pose(stream, pose, flags);
  } catch (const std::bad_alloc&) {
    return fail(NERAF_ERR_OUT_OF_MEMORY, "neraf_stream_set_pose: out of memory");
  } catch (...) {
    return fail(NERAF_ERR_INTERNAL, "neraf_stream_set_pose: unexpected error");
  }
}

extern "C" NERAF_RT_API neraf_status neraf_stream_set_rir(neraf_stream* stream, const float* rir,
                                                          int channels, size_t length) {
  try {
    return set_rir(stream, rir, channels, length);
  } catch (const std::bad_alloc&) {
    return fail(NERAF_ERR_OUT_OF_MEMORY, "neraf_stream_set_rir: out of memory");
  } catch (...) {
    return fail(NERAF_ERR_INTERNAL, "neraf_stream_set_rir: unexpected error");
  }
}

extern "C" NERAF_RT_API neraf_status neraf_stream_wait(neraf_stream* stream, int timeout_ms) {
  try {
    return wait(stream, timeout_ms);
  } catch (const std::bad_alloc&) {
    return fail(NERAF_ERR_OUT_OF_MEMORY, "neraf_stream_wait: out of memory");
  } catch (...) {
    return fail(NERAF_ERR_INTERNAL, "neraf_stream_wait: unexpected error");
  }
}

extern "C" NERAF_RT_API neraf_status neraf_stream_process(neraf_stream* stream, const float* in,
                                                          float* out) {
  // Real-time path: no allocation, no lock. Only the error paths (NULL arguments, a programming
  // error) store a message, which may allocate.
  if (!stream || !in || !out)
    return fail(NERAF_ERR_INVALID_ARGUMENT,
                !stream ? "neraf_stream_process: stream is NULL"
                        : !in ? "neraf_stream_process: in is NULL" : "neraf_stream_process: out is NULL");
  stream->convolver->process(in, out);  // throws nothing
  return NERAF_OK;
}
