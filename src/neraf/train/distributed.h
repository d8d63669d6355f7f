#pragma once
// Data-parallel training over PyTorch's c10d (TCPStore for the rendezvous, ProcessGroupGloo for
// the collectives, both from LibTorch itself; no protocol of our own).
//
// Every rank holds the whole model. Each step every rank draws the same global batch from the
// same (checkpointed) generator and works on its own contiguous slice of it (train/trainer.h,
// StepContext::shard); the gradients are then averaged over the ranks (flattened buckets whose
// all-reduces start inside the backward pass as soon as their gradients are final, waited before
// the optimizer steps), so the step equals one process's step on the global batch up to float
// rounding. Rank 0 alone writes the run folder.
//
// Failures never hang: the rendezvous and every collective wait at most `timeout_s` (a rank that
// died usually shows as "connection closed" at once); they become one neraf::Error line naming
// the rank and the timeout. The c10d headers stay in distributed.cpp.
#include <ATen/core/Tensor.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace neraf::train {

struct DistributedConfig {
  int world_size = 1;                     // processes in the run (1: no distribution)
  int rank = 0;                           // this process, in [0, world_size)
  std::string master_host = "127.0.0.1";  // where rank 0 listens (its TCPStore)
  int master_port = 29500;                // rank 0's TCP port; Gloo picks its own ports
  double timeout_s = 60;                  // rendezvous and every collective
  // Setup waits that include another rank's data loading (a first feature-cache build can take
  // minutes): at least this long.
  double setup_timeout_s = 600;
  // Gloo's network interface (e.g. "eth0"); empty: the address this host's name resolves to,
  // or loopback when the master is on this machine.
  std::string interface;
  int64_t bucket_bytes = 25 << 20;  // gradient bucket size (PyTorch DDP's default)
  // Start each bucket's all-reduce inside the backward pass (backward_and_average); false: all
  // of them after it, with the same result (--dist-overlap; the CLI's default is on unless the
  // master is a loopback address: ranks that share one machine's cores lost steps/s to it,
  // docs/BENCHMARKS.md).
  bool overlap_backward = true;
  bool enabled() const { return world_size > 1; }
};

// Whether `host` names this machine's loopback (localhost, 127.x.y.z, ::1).
bool is_loopback_host(const std::string& host);

// "HOST:PORT" → host and port; neraf::Error naming `flag` otherwise.
void parse_master(const std::string& text, const std::string& flag, DistributedConfig& out);

// Flattened buckets: consecutive tensors of one dtype whose total size stays within
// `bucket_bytes` (a tensor larger than that is a bucket of its own). Returns, per bucket, the
// indices into `tensors`. Pure; tested against a slow reference.
std::vector<std::vector<size_t>> plan_buckets(const std::vector<at::Tensor>& tensors,
                                              int64_t bucket_bytes);

// The bytes and time of the gradient all-reduces so far (for the benchmark and the log).
struct CommStats {
  int64_t allreduces = 0;  // gradient all-reduce calls (one per step)
  int64_t buckets = 0;
  int64_t overlapped_buckets = 0;  // of those, started inside the backward pass
  int64_t bytes = 0;               // payload all-reduced (each rank's buffer size)
  // Wall time the all-reduces added to the steps: flattening and starting buckets (inside the
  // backward pass too), then waiting for them and copying the averages back. Time that Gloo's
  // threads spent sending while backward went on is not counted: that is the overlap.
  double seconds = 0;
};

class Distributed {
 public:
  // Rendezvous of all ranks: rank 0 listens on master_port, the others connect; every rank then
  // checks that they agree on world size and that no rank is taken twice. neraf::Error for an
  // unreachable master, a port in use, a disagreeing world size or a rank that did not join
  // within timeout_s.
  explicit Distributed(const DistributedConfig& config);
  ~Distributed();
  Distributed(const Distributed&) = delete;
  Distributed& operator=(const Distributed&) = delete;

  int rank() const { return config_.rank; }
  int world_size() const { return config_.world_size; }
  const DistributedConfig& config() const { return config_; }

  // Rank 0's `value` under `key`, on every rank (rank 0 passes it, the others receive it).
  std::string share_from_rank0(const std::string& key, const std::string& value);
  // Every rank's JSON text `value` must equal rank 0's: neraf::Error on every rank naming the
  // first rank and setting that differ (`what` says what was compared, e.g. "training config").
  void check_same_json(const std::string& key, const std::string& what, const std::string& value);

  // In place, from rank 0 (flattened buckets).
  void broadcast(const std::vector<at::Tensor>& tensors);
  // loss.backward() (when it requires grad); then each defined gradient of `params` (deduplicated
  // by identity) becomes the mean over the ranks, a parameter without one keeps none. The
  // all-reduces overlap the backward pass, as PyTorch's DDP reducer does it: a post-hook on each
  // parameter's gradient accumulator (kept alive, so the hook serves every step) counts the
  // gradients as they become final, and a bucket's all-reduce starts as soon as its last
  // gradient is in. Buckets hold the parameters that the loss's graph reaches, last parameter
  // first (roughly the order in which backward finishes them), and start strictly in bucket
  // order, so every rank issues the same collectives in the same order.
  void backward_and_average(const at::Tensor& loss, const std::vector<at::Tensor>& params);
  // In place: the element-wise sum over the ranks (small tensors: losses, flags, norms).
  void sum(at::Tensor& tensor);
  void barrier();

  const CommStats& stats() const { return stats_; }

 private:
  struct Impl;
  struct Overlap;  // backward_and_average's hooks and this step's buckets
  // Rethrows what a c10d call threw as neraf::Error naming the operation and the timeout.
  [[noreturn]] void fail(const std::string& operation, const std::exception& e) const;

  DistributedConfig config_;
  std::unique_ptr<Impl> impl_;
  std::unique_ptr<Overlap> overlap_;
  CommStats stats_;
};

}  // namespace neraf::train
