// Data-parallel training (train/distributed.h): the bucket plan, the sharded spectral-convergence
// loss, the gradient all-reduce inside the backward pass, and K joint steps with 2 ranks (threads
// of this process, Gloo over 127.0.0.1) against one process with the same global batch.
#include "neraf/train/distributed.h"

#include <ATen/CPUGeneratorImpl.h>
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <torch/torch.h>
#include <unistd.h>

#include <exception>
#include <mutex>
#include <thread>
#include <unordered_set>

#include "../infer/audio_test_util.h"
#include "neraf/acoustic/losses.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"

namespace neraf::train {
namespace {

using infer::TrainConfig;
using infer::fixtures::make_image_set;
using infer::fixtures::make_temp_dir;
using infer::fixtures::tiny_joint_config;
using infer::fixtures::tiny_rir_set;

int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  EXPECT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len), 0);
  ::close(fd);
  return ntohs(a.sin_port);
}

TEST(Distributed, BucketPlanCoversEveryTensorOnceGreedilyAndByDtype) {
  torch::manual_seed(3);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<at::Tensor> ts;
    const int n = 1 + trial % 17;
    for (int i = 0; i < n; ++i) {
      const int64_t numel = torch::randint(1, 300, {1}).item<int64_t>();
      ts.push_back(torch::zeros({numel}, (i % 5 == 4) ? torch::kFloat64 : torch::kFloat32));
    }
    const int64_t limit = 64 + 97 * trial;
    const auto plan = plan_buckets(ts, limit);
    // Slow reference: walk the tensors and start a bucket exactly when the greedy rule says so.
    std::vector<std::vector<size_t>> ref;
    int64_t used = 0;
    for (size_t i = 0; i < ts.size(); ++i) {
      const int64_t b = ts[i].numel() * ts[i].element_size();
      const bool same_dtype =
          !ref.empty() && ts[ref.back().back()].scalar_type() == ts[i].scalar_type();
      if (ref.empty() || !same_dtype || used + b > limit) {
        ref.push_back({});
        used = 0;
      }
      ref.back().push_back(i);
      used += b;
    }
    ASSERT_EQ(plan, ref) << "trial " << trial;
    for (const auto& bucket : plan) {
      int64_t bytes = 0;
      for (size_t i : bucket) bytes += ts[i].numel() * ts[i].element_size();
      EXPECT_TRUE(bytes <= limit || bucket.size() == 1);  // only a lone big tensor may exceed
    }
  }
  EXPECT_TRUE(plan_buckets({}, 100).empty());
}

TEST(Distributed, MasterAddressIsParsedOrRefused) {
  DistributedConfig c;
  parse_master("10.0.0.2:1234", "--master", c);
  EXPECT_EQ(c.master_host, "10.0.0.2");
  EXPECT_EQ(c.master_port, 1234);
  parse_master("[::1]:29500", "--master", c);
  EXPECT_EQ(c.master_host, "::1");
  for (const char* bad : {"10.0.0.2", ":1234", "host:", "host:0", "host:65536", "host:12a"})
    EXPECT_THROW(parse_master(bad, "--master", c), Error) << bad;
}

// Two halves of a batch as two ranks: the mean of their gradients is the whole batch's SC
// gradient, and each rank's reported SC is the whole batch's.
TEST(Distributed, ShardedSpectralConvergenceEqualsTheWholeBatch) {
  torch::manual_seed(5);
  const torch::Tensor gt = torch::randn({8, 2, 5}) * 0.5 - 2;
  const torch::Tensor init = torch::randn({8, 2, 5}) * 0.5 - 2;
  torch::Tensor whole = init.clone().requires_grad_(true);
  const auto full = acoustic::spectral_loss(whole, gt);
  full.sc.backward();

  auto sums = [&](const torch::Tensor& p, const torch::Tensor& g) {
    const auto x = torch::exp(p) - 1e-3, y = torch::exp(g) - 1e-3;
    return torch::stack({(y - x).pow(2).sum(), y.pow(2).sum()});
  };
  torch::Tensor mean_grad = torch::zeros_like(init);
  for (int r = 0; r < 2; ++r) {
    torch::Tensor part = init.narrow(0, 4 * r, 4).clone().requires_grad_(true);
    const torch::Tensor other = sums(init.narrow(0, 4 * (1 - r), 4), gt.narrow(0, 4 * (1 - r), 4));
    const auto t = acoustic::spectral_loss_sharded(
        part, gt.narrow(0, 4 * r, 4), [&](torch::Tensor& s) { s += other; }, 2);
    EXPECT_NEAR(t.sc.item<double>(), full.sc.item<double>(), 1e-6);
    t.sc.backward();
    mean_grad.narrow(0, 4 * r, 4).copy_(part.grad() / 2);
  }
  EXPECT_LT((mean_grad - whole.grad()).abs().max().item<double>(),
            1e-6 * whole.grad().abs().max().item<double>());
}

// The all-reduce that overlaps the backward pass, against the mean of the ranks' gradients from a
// plain backward: parameters reached several times, one in two optimizer groups (listed twice),
// one the graph does not reach (keeps no gradient), one frozen, many small buckets, two steps
// (the hooks serve every graph); and the same with the overlap off.
TEST(Distributed, GradientsAreAveragedWhileBackwardRuns) {
  struct Model {
    torch::Tensor a, b, d, unused, frozen;
    // Each draw has its own generator: the ranks' threads run at once, and seeding the global
    // generator from both made one rank draw the other's numbers (seen on CI).
    explicit Model(uint64_t seed) {
      at::Generator gen = at::detail::createCPUGenerator(seed);
      a = torch::randn({300}, gen).requires_grad_(true);
      b = torch::randn({40, 50}, gen).requires_grad_(true);
      d = torch::randn({100}, gen).requires_grad_(true);
      unused = torch::randn({64}, gen).requires_grad_(true);
      frozen = torch::randn({100}, gen);
    }
    std::vector<torch::Tensor> params() const { return {a, b, d, b, unused, frozen}; }
    torch::Tensor loss(int rank, int step) const {
      at::Generator gen = at::detail::createCPUGenerator(100 * step + rank);  // this rank's "batch"
      const torch::Tensor x = torch::randn({300}, gen), y = torch::randn({100}, gen);
      return (a * x).pow(2).sum() + b.sum() * d.sum() + (d * y * frozen).sum() + b.pow(3).mean();
    }
  };
  const int W = 2, steps = 2;
  // The reference: each rank's gradients from a plain backward, averaged here.
  std::vector<std::vector<torch::Tensor>> want(steps);
  for (int s = 0; s < steps; ++s) {
    std::vector<torch::Tensor> sum;
    for (int r = 0; r < W; ++r) {
      Model m(7);
      m.loss(r, s).backward();
      const std::vector<torch::Tensor> g = {m.a.grad(), m.b.grad(), m.d.grad()};
      for (size_t i = 0; i < g.size(); ++i) {
        if (r == 0)
          sum.push_back(g[i].clone());
        else
          sum[i] += g[i];
      }
    }
    for (auto& t : sum) want[static_cast<size_t>(s)].push_back(t / W);
  }

  for (const bool overlap : {true, false}) {
    SCOPED_TRACE(overlap ? "--dist-overlap on" : "--dist-overlap off");
    const int port = free_port();
    std::vector<std::vector<std::vector<torch::Tensor>>> got(W);
    std::vector<CommStats> stats(W);
    std::vector<std::string> errors(W);
    auto rank_main = [&](int rank) {
      try {
        DistributedConfig dc;
        dc.world_size = W;
        dc.rank = rank;
        dc.master_port = port;
        dc.timeout_s = 30;
        dc.bucket_bytes = 4000;  // a, d: one bucket each; b (8000 bytes): its own
        dc.overlap_backward = overlap;
        Distributed dist(dc);
        Model m(7);
        for (int s = 0; s < steps; ++s) {
          for (auto& p : m.params()) p.mutable_grad() = torch::Tensor();
          dist.backward_and_average(m.loss(rank, s), m.params());
          EXPECT_FALSE(m.unused.grad().defined());
          EXPECT_FALSE(m.frozen.grad().defined());
          got[rank].push_back({m.a.grad().clone(), m.b.grad().clone(), m.d.grad().clone()});
        }
        stats[rank] = dist.stats();
        dist.barrier();
      } catch (const std::exception& e) {
        errors[rank] = e.what();
      }
    };
    std::thread t0(rank_main, 0), t1(rank_main, 1);
    t0.join();
    t1.join();
    for (int r = 0; r < W; ++r) {
      ASSERT_EQ(errors[r], "") << "rank " << r;
      ASSERT_EQ(got[r].size(), static_cast<size_t>(steps));
      for (int s = 0; s < steps; ++s)
        for (size_t i = 0; i < 3; ++i) {
          const auto& g = got[r][s][i];
          const auto& w = want[s][i];
          EXPECT_LE((g - w).abs().max().item<double>(), 1e-6 * w.abs().max().item<double>())
              << "rank " << r << " step " << s << " parameter " << i;
        }
      EXPECT_EQ(stats[r].allreduces, steps);
      EXPECT_EQ(stats[r].buckets, 3 * steps);
      // Overlapped, every bucket's gradients were final before backward returned, so each
      // started inside it; not overlapped, none did.
      EXPECT_EQ(stats[r].overlapped_buckets, overlap ? stats[r].buckets : 0);
      EXPECT_EQ(stats[r].bytes, steps * (300 + 2000 + 100) * 4);
    }
    for (int s = 0; s < steps; ++s)
      for (size_t i = 0; i < 3; ++i) EXPECT_TRUE(got[0][s][i].equal(got[1][s][i]));
  }
}

// Every distinct parameter of the trainer's branches, cloned.
std::vector<torch::Tensor> parameters_of(Trainer& t) {
  std::vector<torch::Tensor> out;
  std::unordered_set<const void*> seen;
  for (const char* name : {"vision", "audio"})
    if (Branch* b = t.branch(name))
      for (const auto& g : b->param_groups())
        for (const auto& p : g.params)
          if (seen.insert(p.unsafeGetTensorImpl()).second) out.push_back(p.detach().clone());
  return out;
}

struct RunResult {
  std::vector<torch::Tensor> params;  // rank 0's after the steps
  std::vector<double> losses;         // rank 0's reported total loss per step
  double max_rank_difference = 0;     // largest |rank r − rank 0| over the parameters
  CommStats comm;                     // rank 0's
};

RunResult train_ranks(const TrainConfig& cfg, int world, int steps, const data::ImageSet& images,
                      const data::RirSet& rirs, int64_t bucket_bytes) {
  std::vector<RunResult> results(static_cast<size_t>(world));
  std::vector<std::exception_ptr> errors(static_cast<size_t>(world));
  const int port = free_port();
  std::mutex init_mutex;
  auto rank_main = [&](int rank) {
    try {
      std::unique_ptr<Distributed> dist;
      if (world > 1) {
        DistributedConfig dc;
        dc.world_size = world;
        dc.rank = rank;
        dc.master_port = port;
        dc.timeout_s = 30;
        dc.bucket_bytes = bucket_bytes;
        dist = std::make_unique<Distributed>(dc);
      }
      std::unique_ptr<Trainer> trainer;
      {
        // LibTorch's module initialisers draw from the global generator (run_training seeds it
        // with the run's seed in each process), so the ranks' threads build one at a time.
        std::lock_guard<std::mutex> lock(init_mutex);
        torch::manual_seed(cfg.seed);
        trainer = make_trainer(cfg, &images, torch::kCPU, &rirs);
      }
      trainer->set_distributed(dist.get());
      trainer->broadcast_parameters();
      RunResult& out = results[static_cast<size_t>(rank)];
      for (int s = 0; s < steps; ++s) out.losses.push_back(trainer->step().loss);
      out.params = parameters_of(*trainer);
      if (dist) {
        out.comm = dist->stats();
        dist->barrier();
      }
    } catch (...) {
      errors[static_cast<size_t>(rank)] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  for (int r = 0; r < world; ++r) threads.emplace_back(rank_main, r);
  for (auto& t : threads) t.join();
  for (auto& e : errors)
    if (e) std::rethrow_exception(e);
  RunResult out = results[0];
  for (int r = 1; r < world; ++r)
    for (size_t i = 0; i < out.params.size(); ++i)
      out.max_rank_difference = std::max(
          out.max_rank_difference,
          (results[static_cast<size_t>(r)].params[i] - out.params[i]).abs().max().item<double>());
  return out;
}

double max_difference(const std::vector<torch::Tensor>& a, const std::vector<torch::Tensor>& b) {
  EXPECT_EQ(a.size(), b.size());
  double m = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i)
    m = std::max(m, (a[i] - b[i]).abs().max().item<double>());
  return m;
}

TEST(Distributed, TwoRanksTrainWhatOneProcessTrainsOnTheSameGlobalBatch) {
  torch::set_num_threads(1);
  const std::string dir = make_temp_dir("dist");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set(3, 12);
  TrainConfig cfg = tiny_joint_config();
  cfg.audio.decay_weight = 1.0;  // the energy-decay loss on whole RIRs too (same on every rank)
  cfg.audio.decay_rirs = 2;
  const int K = 6;
  std::vector<torch::Tensor> init;
  {
    torch::manual_seed(cfg.seed);
    auto t = make_trainer(cfg, &images, torch::kCPU, &rirs);
    init = parameters_of(*t);
  }
  const RunResult one = train_ranks(cfg, 1, K, images, rirs, 25 << 20);
  const RunResult two = train_ranks(cfg, 2, K, images, rirs, 4096);  // many small buckets
  // The ranks hold identical parameters (the same averaged gradients, the same Adam).
  EXPECT_EQ(two.max_rank_difference, 0.0);
  // The trainer's all-reduces ran inside its backward passes (the last bucket may start after).
  EXPECT_EQ(two.comm.allreduces, K);
  EXPECT_GE(two.comm.overlapped_buckets, two.comm.buckets - K);
  EXPECT_GT(two.comm.overlapped_buckets, 0);
  const double moved = max_difference(one.params, init);
  const double diff = max_difference(one.params, two.params);
  ASSERT_GT(moved, 1e-3);  // the steps did change the model
  // Float rounding only: the two halves' gradients are summed in another order. Adam moves a
  // parameter by about its learning rate whatever the gradient's size, so a component within
  // rounding of zero can take the other sign on one side: a few elements may differ by a few
  // learning rates (on this Intel Xeon: 347 of 3.6 M beyond 1e-5, at most 2.4e-4, against all but
  // 0.05 % for another seed), never the bulk.
  int64_t elements = 0, apart = 0;
  for (size_t i = 0; i < one.params.size(); ++i) {
    elements += one.params[i].numel();
    apart += (one.params[i] - two.params[i]).abs().gt(1e-5).sum().item<int64_t>();
  }
  EXPECT_LT(apart, elements / 1000) << "of " << elements << " elements";
  EXPECT_LT(diff, 1e-2 * std::max(1.0, moved)) << "moved " << moved;
  for (int s = 0; s < K; ++s)
    EXPECT_NEAR(two.losses[static_cast<size_t>(s)], one.losses[static_cast<size_t>(s)],
                1e-5 * std::abs(one.losses[static_cast<size_t>(s)]))
        << "step " << s;
  // The comparison can fail: another seed's batches give other parameters.
  TrainConfig other = cfg;
  other.seed = cfg.seed + 1;
  const RunResult control = train_ranks(other, 1, K, images, rirs, 25 << 20);
  const double control_diff = max_difference(one.params, control.params);
  EXPECT_GT(control_diff, 100 * diff);
  int64_t control_apart = 0;
  for (size_t i = 0; i < one.params.size(); ++i)
    control_apart += (one.params[i] - control.params[i]).abs().gt(1e-5).sum().item<int64_t>();
  EXPECT_GT(control_apart, elements / 2);
  std::printf(
      "max |parameter change| %.3g; max |1 process - 2 ranks| %.3g (%lld of %lld elements beyond "
      "1e-5); another seed %.3g (%lld)\n",
      moved, diff, static_cast<long long>(apart), static_cast<long long>(elements), control_diff,
      static_cast<long long>(control_apart));
}

TEST(Distributed, WorldSizeMismatchAndBadRankAreClearErrors) {
  DistributedConfig bad;
  bad.world_size = 2;
  bad.rank = 2;
  EXPECT_THROW(Distributed{bad}, Error);
  const int port = free_port();
  std::string messages[2];
  auto rank_main = [&](int rank, int world) {
    DistributedConfig dc;
    dc.world_size = world;
    dc.rank = rank;
    dc.master_port = port;
    dc.timeout_s = 5;
    try {
      Distributed d(dc);
    } catch (const Error& e) {
      messages[rank] = e.what();
    }
  };
  std::thread a(rank_main, 0, 2), b(rank_main, 1, 3);
  a.join();
  b.join();
  for (const auto& m : messages) {
    EXPECT_NE(m.find("--world-size differs between the ranks: rank 0 has 2, rank 1 has 3"),
              std::string::npos)
        << m;
  }
}

}  // namespace
}  // namespace neraf::train
