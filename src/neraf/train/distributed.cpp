#include "neraf/train/distributed.h"

#include <torch/csrc/autograd/function.h>
#include <torch/csrc/autograd/utils/lambda_post_hook.h>
#include <torch/csrc/autograd/variable.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <torch/csrc/distributed/c10d/PrefixStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>
#include <unordered_map>
#include <unordered_set>

#include "neraf/infer/checkpoint.h"
#include "neraf/util/error.h"

namespace neraf::train {

namespace {

using Clock = std::chrono::steady_clock;

std::chrono::milliseconds millis(double seconds) {
  return std::chrono::milliseconds(static_cast<int64_t>(std::llround(seconds * 1000.0)));
}

std::vector<uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }
std::string text_of(const std::vector<uint8_t>& b) { return {b.begin(), b.end()}; }

// The first line of what LibTorch or Gloo threw, without its backtrace.
std::string first_line(const std::exception& e) {
  std::string what = e.what();
  if (const auto* c10 = dynamic_cast<const c10::Error*>(&e)) what = c10->what_without_backtrace();
  what = what.substr(0, what.find('\n'));
  return what;
}

std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

}  // namespace

bool is_loopback_host(const std::string& host) {
  return host == "localhost" || host.rfind("127.", 0) == 0 || host == "::1";
}

void parse_master(const std::string& text, const std::string& flag, DistributedConfig& out) {
  const size_t colon = text.rfind(':');
  const std::string usage = flag + " " + text + ": expected HOST:PORT (e.g. 127.0.0.1:29500)";
  require(colon != std::string::npos && colon > 0 && colon + 1 < text.size(), usage);
  std::string host = text.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']')  // [::1]:29500
    host = host.substr(1, host.size() - 2);
  const std::string port = text.substr(colon + 1);
  require(port.find_first_not_of("0123456789") == std::string::npos && port.size() <= 5, usage);
  const long value = std::stol(port);
  require(value >= 1 && value <= 65535,
          flag + " " + text + ": the port must be in [1, 65535]; got " + port);
  out.master_host = host;
  out.master_port = static_cast<int>(value);
}

std::vector<std::vector<size_t>> plan_buckets(const std::vector<at::Tensor>& tensors,
                                              int64_t bucket_bytes) {
  std::vector<std::vector<size_t>> buckets;
  int64_t filled = 0;
  c10::ScalarType dtype = c10::ScalarType::Undefined;
  for (size_t i = 0; i < tensors.size(); ++i) {
    const int64_t bytes = tensors[i].numel() * static_cast<int64_t>(tensors[i].element_size());
    const bool fits = filled + bytes <= bucket_bytes;
    if (buckets.empty() || tensors[i].scalar_type() != dtype || !fits) {
      if (buckets.empty() || !buckets.back().empty()) buckets.emplace_back();
      filled = 0;
      dtype = tensors[i].scalar_type();
    }
    buckets.back().push_back(i);
    filled += bytes;
  }
  return buckets;
}

struct Distributed::Impl {
  c10::intrusive_ptr<c10d::Store> store;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> group;
  int64_t next_key = 0;  // one store namespace per share / check call

  // Waits for one store key, `seconds` at most; false when it did not appear.
  bool wait_key(const std::string& key, double seconds) {
    try {
      store->wait({key}, millis(seconds));
      return true;
    } catch (const std::exception& e) {
      const std::string what = first_line(e);
      if (what.find("imeout") != std::string::npos || what.find("imed out") != std::string::npos)
        return false;
      throw;
    }
  }

  // Rank 0, before it throws a verdict the others must read: the store lives in rank 0, so it
  // waits (a few seconds at most) until ranks 1..n-1 acknowledged `base` + rank.
  void wait_acks(const std::string& base, int n, double seconds) {
    for (int q = 1; q < n; ++q) {
      try {
        if (!wait_key(base + std::to_string(q), seconds)) return;
      } catch (const std::exception&) {
        return;  // that rank is gone already
      }
    }
  }
};

// backward_and_average's state. The hooks stay on the accumulators (kept alive here, so every
// step's graph reaches the same ones) and act only while a step is active.
struct Distributed::Overlap {
  struct Hooked {
    at::Tensor param;
    std::shared_ptr<torch::autograd::Node> accumulator;
    uintptr_t key = 0;  // the post-hook, for del_post_hook
  };
  std::vector<Hooked> hooked;
  std::unordered_map<const void*, size_t> index;  // TensorImpl → hooked

  // This step, set up before loss.backward():
  bool active = false;
  std::vector<int64_t> bucket_of;            // per hooked parameter: its bucket, −1 if none
  std::vector<bool> arrived;                 // per hooked parameter: its gradient is final
  std::vector<std::vector<size_t>> buckets;  // hooked indices
  std::vector<int64_t> pending;              // per bucket: gradients still to come
  size_t next = 0;                           // the first bucket not started
  std::vector<std::vector<at::Tensor>> flats;
  std::vector<c10::intrusive_ptr<c10d::Work>> works;
  std::exception_ptr error;  // what starting an all-reduce threw inside the backward pass
  int64_t started_in_backward = 0;
  double seconds = 0;  // spent in the hooks

  ~Overlap() {
    for (Hooked& h : hooked) h.accumulator->del_post_hook(h.key);
  }

  // Starts bucket `b`: its gradients flattened (zeros for a parameter the graph reached that got
  // none, identically on every rank), all-reduced by Gloo's threads.
  void start(size_t b, c10d::ProcessGroupGloo& group, CommStats& stats) {
    torch::NoGradGuard no_grad;
    std::vector<at::Tensor> parts;
    for (size_t i : buckets[b]) {
      const at::Tensor& p = hooked[i].param;
      const at::Tensor& g = p.grad();
      parts.push_back(g.defined() ? g.reshape({-1}) : torch::zeros({p.numel()}, p.options()));
    }
    flats[b] = {torch::cat(parts)};
    stats.bytes += flats[b][0].numel() * static_cast<int64_t>(flats[b][0].element_size());
    works[b] = group.allreduce(flats[b]);
  }

  // A post-hook: parameter i's gradient is final; start every bucket that is complete, in order.
  void arrive(size_t i, c10d::ProcessGroupGloo& group, CommStats& stats) {
    if (!active || bucket_of[i] < 0 || arrived[i] || error) return;
    const auto t0 = Clock::now();
    arrived[i] = true;
    --pending[static_cast<size_t>(bucket_of[i])];
    try {
      for (; next < buckets.size() && pending[next] == 0; ++next, ++started_in_backward)
        start(next, group, stats);
    } catch (...) {
      error = std::current_exception();  // rethrown after backward, as neraf::Error
    }
    seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
};

namespace {

// The autograd nodes that backward from `loss` runs (the accumulators of the parameters it
// reaches among them).
std::unordered_set<const torch::autograd::Node*> graph_nodes(const at::Tensor& loss) {
  std::unordered_set<const torch::autograd::Node*> seen;
  std::vector<torch::autograd::Node*> todo;
  if (torch::autograd::Node* root = loss.grad_fn().get()) {
    seen.insert(root);
    todo.push_back(root);
  }
  while (!todo.empty()) {
    torch::autograd::Node* n = todo.back();
    todo.pop_back();
    for (const torch::autograd::Edge& e : n->next_edges())
      if (e.function && seen.insert(e.function.get()).second) todo.push_back(e.function.get());
  }
  return seen;
}

}  // namespace

Distributed::Distributed(const DistributedConfig& config)
    : config_(config), impl_(std::make_unique<Impl>()), overlap_(std::make_unique<Overlap>()) {
  const int W = config_.world_size, r = config_.rank;
  require(W >= 1, "--world-size: must be at least 1");
  require(r >= 0 && r < W, "--rank " + std::to_string(r) + ": must be below --world-size " +
                               std::to_string(W) + " (ranks are 0.." + std::to_string(W - 1) + ")");
  const std::string master = config_.master_host + ":" + std::to_string(config_.master_port);
  const std::string timeout = "--dist-timeout " + seconds_text(config_.timeout_s) + " s";
  // Rendezvous: rank 0 hosts the store; the others retry connecting until the timeout.
  try {
    c10d::TCPStoreOptions o;
    o.port = static_cast<std::uint16_t>(config_.master_port);
    o.isServer = r == 0;
    o.waitWorkers = false;  // joining is checked below, with errors that name the rank
    o.timeout = millis(config_.timeout_s);
    impl_->store = c10::make_intrusive<c10d::TCPStore>(config_.master_host, o);
  } catch (const std::exception& e) {
    const std::string what = first_line(e);
    if (r == 0)
      throw Error("--master " + master + ": rank 0 cannot listen on port " +
                  std::to_string(config_.master_port) + " (" + what +
                  "); the port is probably in use: choose another --master port");
    throw Error("--master " + master + ": rank " + std::to_string(r) +
                " cannot reach rank 0 within " + timeout + " (" + what +
                "); start rank 0 first, check the address and port and that no firewall "
                "blocks them");
  }
  // Every rank must be started with the same world size, each rank once.
  try {
    auto& store = *impl_->store;
    const std::string me = std::to_string(r);
    if (store.add("neraf/claims/" + me, 1) > 1)
      throw Error("--rank " + me + ": another process already joined as rank " + me + " at " +
                  master + "; give each process its own --rank");
    store.set("neraf/join/" + me, bytes_of(std::to_string(W)));
    if (r == 0) {
      std::string verdict;
      for (int q = 1; q < W && verdict.empty(); ++q) {
        const std::string key = "neraf/join/" + std::to_string(q);
        if (!impl_->wait_key(key, config_.timeout_s)) {
          verdict = "rank " + std::to_string(q) + " of " + std::to_string(W) + " did not join " +
                    master + " within " + timeout + "; start every rank with --world-size " +
                    std::to_string(W);
          break;
        }
        const std::string theirs = text_of(store.get(key));
        if (theirs != std::to_string(W))
          verdict = "--world-size differs between the ranks: rank 0 has " + std::to_string(W) +
                    ", rank " + std::to_string(q) + " has " + theirs +
                    "; start every rank with the same --world-size";
      }
      store.set("neraf/verdict", bytes_of(std::to_string(W) + "\n" + verdict));
      if (!verdict.empty()) {
        impl_->wait_acks("neraf/verdict_ack/", W, std::min(config_.timeout_s, 10.0));
        throw Error(verdict);
      }
    } else {
      if (!impl_->wait_key("neraf/verdict", config_.setup_timeout_s + config_.timeout_s))
        throw Error("rank " + me + ": rank 0 at " + master + " did not confirm the ranks within " +
                    seconds_text(config_.setup_timeout_s + config_.timeout_s) + " s");
      const std::string v = text_of(store.get("neraf/verdict"));
      store.set("neraf/verdict_ack/" + me, bytes_of("1"));
      const std::string ws = v.substr(0, v.find('\n'));
      const std::string message = v.substr(v.find('\n') + 1);
      if (!message.empty()) throw Error(message);
      if (ws != std::to_string(W))
        throw Error("--world-size differs between the ranks: rank 0 has " + ws + ", rank " + me +
                    " has " + std::to_string(W) + "; start every rank with the same --world-size");
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail("the rendezvous at " + master, e);
  }
  // The process group: Gloo over TCP, every collective bounded by the timeout.
  try {
    auto options = c10d::ProcessGroupGloo::Options::create(millis(config_.timeout_s));
    if (!config_.interface.empty())
      options->devices.push_back(
          c10d::ProcessGroupGloo::createDeviceForInterface(config_.interface));
    else if (is_loopback_host(config_.master_host))
      options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1"));
    else
      options->devices.push_back(c10d::ProcessGroupGloo::createDefaultDevice());
    options->threads = 2;  // the async bucket all-reduces run on these
    auto prefixed = c10::make_intrusive<c10d::PrefixStore>("gloo", impl_->store);
    impl_->group = c10::make_intrusive<c10d::ProcessGroupGloo>(prefixed, r, W, options);
  } catch (const std::exception& e) {
    fail("connecting the ranks (Gloo" +
             (config_.interface.empty() ? std::string() : " on " + config_.interface) + ")",
         e);
  }
}

Distributed::~Distributed() = default;

void Distributed::fail(const std::string& operation, const std::exception& e) const {
  throw Error("distributed training, rank " + std::to_string(config_.rank) + " of " +
              std::to_string(config_.world_size) + ": " + operation + " failed (" + first_line(e) +
              "); another rank stopped or cannot be reached (each wait is " +
              "bounded by --dist-timeout " + seconds_text(config_.timeout_s) + " s)");
}

std::string Distributed::share_from_rank0(const std::string& key, const std::string& value) {
  const std::string k = "neraf/share/" + std::to_string(impl_->next_key++) + "/" + key;
  try {
    if (config_.rank == 0) {
      impl_->store->set(k, bytes_of(value));
      return value;
    }
    if (!impl_->wait_key(k, config_.setup_timeout_s))
      throw Error("distributed training, rank " + std::to_string(config_.rank) + ": rank 0 did " +
                  "not send its " + key + " within " + seconds_text(config_.setup_timeout_s) +
                  " s; it stopped or is still loading its data");
    return text_of(impl_->store->get(k));
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail("receiving rank 0's " + key, e);
  }
}

void Distributed::check_same_json(const std::string& key, const std::string& what,
                                  const std::string& value) {
  const std::string theirs = share_from_rank0(key, value);
  const std::string base = "neraf/check/" + std::to_string(impl_->next_key++) + "/";
  const int r = config_.rank;
  try {
    auto& store = *impl_->store;
    if (r != 0) {
      std::string message;
      const nlohmann::json a = nlohmann::json::parse(theirs), b = nlohmann::json::parse(value);
      if (a != b)
        message = what + " differs between rank 0 and rank " + std::to_string(r) + " (" +
                  infer::first_difference(a, b) + "); start every rank alike";
      store.set(base + std::to_string(r), bytes_of(message));
      if (!impl_->wait_key(base + "verdict", config_.setup_timeout_s))
        throw Error("distributed training, rank " + std::to_string(r) + ": rank 0 did not " +
                    "confirm the " + what + " within " + seconds_text(config_.setup_timeout_s) +
                    " s");
      const std::string verdict = text_of(store.get(base + "verdict"));
      store.set(base + "ack" + std::to_string(r), bytes_of("1"));
      if (!verdict.empty()) throw Error(verdict);
      return;
    }
    std::string verdict;
    for (int q = 1; q < config_.world_size; ++q) {
      if (!impl_->wait_key(base + std::to_string(q), config_.setup_timeout_s)) {
        verdict = "rank " + std::to_string(q) + " did not report its " + what + " within " +
                  seconds_text(config_.setup_timeout_s) + " s; it stopped or is still loading";
        break;
      }
      const std::string m = text_of(store.get(base + std::to_string(q)));
      if (!m.empty() && verdict.empty()) verdict = m;
    }
    store.set(base + "verdict", bytes_of(verdict));
    if (!verdict.empty()) {
      impl_->wait_acks(base + "ack", config_.world_size, std::min(config_.timeout_s, 10.0));
      throw Error(verdict);
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail("comparing the " + what, e);
  }
}

void Distributed::broadcast(const std::vector<at::Tensor>& tensors) {
  torch::NoGradGuard no_grad;
  try {
    for (const auto& bucket : plan_buckets(tensors, config_.bucket_bytes)) {
      std::vector<at::Tensor> parts;
      for (size_t i : bucket) parts.push_back(tensors[i].reshape({-1}));
      std::vector<at::Tensor> flat{torch::cat(parts)};
      c10d::BroadcastOptions o;
      o.rootRank = 0;
      impl_->group->broadcast(flat, o)->wait(millis(config_.timeout_s));
      if (config_.rank == 0) continue;
      int64_t offset = 0;
      for (size_t i : bucket) {
        const int64_t n = tensors[i].numel();
        at::Tensor t = tensors[i];
        t.copy_(flat[0].narrow(0, offset, n).view(t.sizes()));
        offset += n;
      }
    }
  } catch (const std::exception& e) {
    fail("the broadcast of rank 0's parameters", e);
  }
}

void Distributed::backward_and_average(const at::Tensor& loss,
                                       const std::vector<at::Tensor>& params) {
  Overlap& o = *overlap_;
  c10d::ProcessGroupGloo* group = impl_->group.get();
  CommStats* stats = &stats_;
  // Each distinct parameter that takes gradients gets its hook once.
  std::vector<size_t> order;  // hooked indices, in the order of `params`, each once
  std::vector<bool> listed;   // [hooked]: already in `order`
  for (const at::Tensor& p : params) {
    if (!p.requires_grad()) continue;
    auto [it, added] = o.index.emplace(p.unsafeGetTensorImpl(), o.hooked.size());
    if (added) {
      Overlap::Hooked h{p, torch::autograd::impl::grad_accumulator(p), 0};
      const size_t i = it->second;
      h.key = h.accumulator->add_post_hook(std::make_unique<torch::autograd::utils::LambdaPostHook>(
          [&o, group, stats, i](const torch::autograd::variable_list& outputs,
                                const torch::autograd::variable_list&) {
            o.arrive(i, *group, *stats);
            return outputs;
          }));
      o.hooked.push_back(std::move(h));
    }
    if (listed.size() < o.hooked.size()) listed.resize(o.hooked.size(), false);
    if (!listed[it->second]) {
      listed[it->second] = true;
      order.push_back(it->second);
    }
  }

  // This step's buckets: the parameters the graph reaches, last first.
  const auto t0 = Clock::now();
  const auto nodes =
      loss.requires_grad() ? graph_nodes(loss) : std::unordered_set<const torch::autograd::Node*>{};
  std::vector<size_t> reached;
  for (auto it = order.rbegin(); it != order.rend(); ++it)
    if (nodes.count(o.hooked[*it].accumulator.get())) reached.push_back(*it);
  std::vector<at::Tensor> tensors;
  for (size_t i : reached) tensors.push_back(o.hooked[i].param);
  o.buckets.clear();
  for (const auto& bucket : plan_buckets(tensors, config_.bucket_bytes)) {
    o.buckets.emplace_back();
    for (size_t k : bucket) o.buckets.back().push_back(reached[k]);
  }
  o.bucket_of.assign(o.hooked.size(), -1);
  o.arrived.assign(o.hooked.size(), false);
  o.pending.assign(o.buckets.size(), 0);
  for (size_t b = 0; b < o.buckets.size(); ++b)
    for (size_t i : o.buckets[b]) {
      o.bucket_of[i] = static_cast<int64_t>(b);
      ++o.pending[b];
    }
  o.next = 0;
  o.flats.assign(o.buckets.size(), {});
  o.works.assign(o.buckets.size(), {});
  o.error = nullptr;
  o.started_in_backward = 0;
  o.seconds = 0;
  double seconds = std::chrono::duration<double>(Clock::now() - t0).count();

  if (loss.requires_grad()) {
    o.active = config_.overlap_backward;
    try {
      loss.backward();
    } catch (...) {
      o.active = false;
      throw;
    }
    o.active = false;
  }

  const auto t1 = Clock::now();
  torch::NoGradGuard no_grad;
  try {
    if (o.error) std::rethrow_exception(o.error);
    for (; o.next < o.buckets.size(); ++o.next) o.start(o.next, *group, stats_);
    for (size_t b = 0; b < o.buckets.size(); ++b) {
      o.works[b]->wait(millis(config_.timeout_s));
      const at::Tensor flat = o.flats[b][0].div_(config_.world_size);
      int64_t offset = 0;
      for (size_t i : o.buckets[b]) {
        at::Tensor g = o.hooked[i].param.grad();
        const int64_t n = o.hooked[i].param.numel();
        if (g.defined()) g.copy_(flat.narrow(0, offset, n).view(g.sizes()));
        offset += n;
      }
    }
  } catch (const std::exception& e) {
    fail("the gradient all-reduce", e);
  }
  stats_.allreduces += 1;
  stats_.buckets += static_cast<int64_t>(o.buckets.size());
  stats_.overlapped_buckets += o.started_in_backward;
  seconds += o.seconds + std::chrono::duration<double>(Clock::now() - t1).count();
  stats_.seconds += seconds;
}

void Distributed::sum(at::Tensor& tensor) {
  torch::NoGradGuard no_grad;
  try {
    std::vector<at::Tensor> v{tensor.is_contiguous() ? tensor : tensor.contiguous()};
    impl_->group->allreduce(v)->wait(millis(config_.timeout_s));
    if (!v[0].is_same(tensor)) tensor.copy_(v[0]);
  } catch (const std::exception& e) {
    fail("an all-reduce of the step's losses", e);
  }
}

void Distributed::barrier() {
  try {
    impl_->group->barrier()->wait(millis(config_.timeout_s));
  } catch (const std::exception& e) {
    fail("a barrier", e);
  }
}

}  // namespace neraf::train
