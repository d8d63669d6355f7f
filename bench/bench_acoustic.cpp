// Acoustic-branch benchmarks: one training step (ResNet3D fwd+bwd on the grid + NAcF fwd+bwd on
// 2048 slices + SC+SLMSE loss), its parts, the Adam step, and render_stft latency for one RIR.
// Shapes: SoundSpaces (C = 2, F = 257, max_len = 78 frames). Presets cpu (32³ grid, small ResNet,
// NAcF 5×512) and paper (128³, ResNet3D-50/layer3, NAcF 1187→5096→…→512), fp32 and bf16 NAcF trunk.
// The steps report their FLOPs (gflop_per_step, gflop_per_s) and BM_PeakSgemm this machine's
// fastest fp32 rate, so a step's time can be set against the least its arithmetic needs.
//
//   build/neraf_bench_acoustic --benchmark_out=build/bench/acoustic.json
//   build/neraf_bench_acoustic --benchmark_filter=cpu
#include <ATen/autocast_mode.h>
#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bench_main.h"
#include "neraf/acoustic/acoustic_model.h"
#include "neraf/acoustic/losses.h"

namespace neraf::acoustic {
namespace {

constexpr int64_t kChannels = 2, kFreq = 257, kMaxLen = 78, kBatch = 2048;

const char* preset_name(int64_t p) { return p == 0 ? "cpu" : "paper"; }

AcousticModelOptions options_for(int64_t preset, bool bf16) {
  auto o = acoustic_preset(preset_name(preset), kChannels, kFreq, kMaxLen);
  o.nacf.bf16 = bf16;
  return o;
}

struct Batch {
  torch::Tensor t, mic, src, rot, gt;
};

Batch make_batch(int64_t b) {
  return {torch::randint(kMaxLen, {b}, torch::kInt64), torch::rand({b, 3}, torch::kFloat64),
          torch::rand({b, 3}, torch::kFloat64), torch::rand({b, 3}, torch::kFloat64),
          torch::randn({b, kChannels, kFreq}) - 4.0};
}

void set_label(benchmark::State& state, int64_t preset, bool bf16) {
  state.SetLabel(std::string(preset_name(preset)) + (bf16 ? "/bf16" : "/fp32") +
                 " threads=" + std::to_string(torch::get_num_threads()));
}

// Multiply-adds of one forward pass, for the FLOP counters (issue 14 §4: how close to the
// machine's limit a step runs). A convolution costs (output voxels) × (weights); the sides follow
// ResNet3d's layers: the stem (stride 2, padding k/2) and the max pool (k3, s2, p1) give ⌈side/2⌉,
// a stage's stride sits on a Bottleneck's 3×3×3 conv (its 1×1×1 conv1 runs at the stage's input
// side) and on a BasicBlock's conv1. Returns {MACs, weights counted}; the caller checks the weights
// against the real module so that this walk cannot drift from it.
std::pair<double, int64_t> resnet3d_forward_macs(const ResNet3dOptions& o, int64_t side) {
  double macs = 0;
  int64_t weights = 0;
  auto add = [&](int64_t in, int64_t out, int64_t kernel, int64_t out_side) {
    const int64_t w = in * out * kernel * kernel * kernel;
    weights += w;
    macs += static_cast<double>(w) * static_cast<double>(out_side * out_side * out_side);
  };
  auto halve = [](int64_t s, int64_t stride) { return (s + stride - 1) / stride; };
  side = halve(side, 2);
  add(o.in_channels, o.stem_channels, o.stem_kernel, side);
  if (o.stem_max_pool) side = halve(side, 2);
  int64_t in = o.stem_channels;
  const int64_t expansion = resnet3d_expansion(o.block);
  for (size_t s = 0; s < o.layers.size(); ++s) {
    for (int64_t b = 0; b < o.layers[s]; ++b) {
      const int64_t stride = b == 0 ? o.strides[s] : 1, planes = o.planes[s];
      const int64_t out = planes * expansion, in_side = side;
      side = halve(side, stride);
      if (o.block == ResBlock::kBottleneck) {
        add(in, planes, 1, in_side);
        add(planes, planes, 3, side);
        add(planes, out, 1, side);
      } else {
        add(in, planes, 3, side);
        add(planes, planes, 3, side);
      }
      if (stride != 1 || in != out) add(in, out, 1, side);
      in = out;
    }
  }
  return {macs, weights};
}

// The weight count of each submodule of type Layer (Conv3d, Linear), in registration order.
template <typename Layer>
std::vector<int64_t> weight_counts(torch::nn::Module& m) {
  std::vector<int64_t> counts;
  for (const auto& sub : m.modules()) {
    if (const auto* layer = sub->as<Layer>()) counts.push_back(layer->weight.numel());
  }
  return counts;
}

int64_t sum(const std::vector<int64_t>& v) {
  return std::accumulate(v.begin(), v.end(), int64_t{0});
}

// A training step's FLOPs: forward 2 × MACs, backward twice that (the gradients of the inputs and
// of the weights of every layer; the grid needs its gradient, as in joint training), so 6 × MACs,
// less 2 × `untracked_input_macs` for a first layer whose input needs no gradient. Element-wise
// work (batch norm, activations, the loss) is left out: a lower bound.
void set_flop_counters(benchmark::State& state, double forward_macs,
                       double untracked_input_macs = 0) {
  const double flops = 6.0 * forward_macs - 2.0 * untracked_input_macs;
  state.counters["gflop_per_step"] = flops / 1e9;
  state.counters["gflop_per_s"] =
      benchmark::Counter(flops / 1e9, benchmark::Counter::kIsIterationInvariantRate);
}

// Full step without the optimiser: grid (requires grad, as the fresh cells do) → ResNet3D →
// NAcF on 2048 slices → loss → backward.
void BM_AcousticStep(benchmark::State& state) {
  const int64_t preset = state.range(0);
  const bool bf16 = state.range(1) != 0;
  torch::manual_seed(0);
  AcousticModel m(options_for(preset, bf16));
  const int64_t s = m->options().grid.resolution;
  auto grid = torch::rand({7, s, s, s}, torch::requires_grad());
  const auto b = make_batch(kBatch);
  for (auto _ : state) {
    m->zero_grad();
    grid.mutable_grad() = torch::Tensor();
    const auto pred = m->forward(grid, b.t, b.mic, b.src, b.rot);
    auto loss = spectral_loss(pred, b.gt);
    loss.total.backward();
    benchmark::DoNotOptimize(loss.total.item<float>());
  }
  const auto [resnet_macs, weights] = resnet3d_forward_macs(m->options().resnet, s);
  state.counters["conv_weights_match"] = weights == sum(weight_counts<torch::nn::Conv3d>(*m));
  // A Linear layer costs its weights × the batch.
  set_flop_counters(state,
                    resnet_macs + double(sum(weight_counts<torch::nn::Linear>(*m))) * kBatch);
  set_label(state, preset, bf16);
}

void BM_ResNet3dFwdBwd(benchmark::State& state) {
  const int64_t preset = state.range(0);
  torch::manual_seed(0);
  const auto o = options_for(preset, false);
  ResNet3d net(o.resnet);
  const int64_t s = o.grid.resolution;
  auto grid = torch::rand({1, 7, s, s, s}, torch::requires_grad());
  for (auto _ : state) {
    net->zero_grad();
    grid.mutable_grad() = torch::Tensor();
    auto y = net->forward(grid);
    y.sum().backward();
    benchmark::DoNotOptimize(y.data_ptr());
  }
  const auto [macs, weights] = resnet3d_forward_macs(o.resnet, s);
  state.counters["conv_weights_match"] = weights == sum(weight_counts<torch::nn::Conv3d>(*net));
  set_flop_counters(state, macs);
  set_label(state, preset, false);
}

// The same fwd+bwd in other number formats and layouts (issue 14 §4: where can ResNet3D's step go
// faster?), variant bits: 1 bf16 weights and grid, 2 channels-last (NDHWC) instead of NCDHW,
// 4 fp32 under CPU autocast to bf16 (bf16 convolutions, fp32 batch norm), 8 fp64 (how exact fp32
// itself is). Counters: the features' and the grid gradient's relative L2 error against fp32
// NCDHW with the same weights and grid.
void BM_ResNet3dLayouts(benchmark::State& state) {
  const int64_t preset = state.range(0);
  const bool bf16 = state.range(1) & 1, channels_last = state.range(1) & 2,
             autocast = state.range(1) & 4, fp64 = state.range(1) & 8;
  const auto o = options_for(preset, false);
  const int64_t s = o.grid.resolution;
  torch::manual_seed(0);
  ResNet3d reference(o.resnet);
  torch::manual_seed(0);
  ResNet3d net(o.resnet);
  const auto format =
      channels_last ? torch::MemoryFormat::ChannelsLast3d : torch::MemoryFormat::Contiguous;
  const auto dtype = bf16 ? torch::kBFloat16 : fp64 ? torch::kFloat64 : torch::kFloat32;
  net->to(dtype);
  for (auto& p : net->parameters()) {
    if (p.dim() == 5) p.set_data(p.contiguous(format));
  }
  const auto grid32 = torch::rand({1, 7, s, s, s});
  // A fixed random projection as the loss: the sum of the features would back-propagate almost
  // nothing through the last BatchNorm (its output's mean is fixed), a gradient of rounding noise.
  const auto probe = torch::randn({1, net->out_features()});
  auto grid = grid32.to(dtype).contiguous(format).detach().requires_grad_();
  auto run = [&] {
    net->zero_grad();
    grid.mutable_grad() = torch::Tensor();
    at::autocast::set_cpu_enabled(autocast);
    at::autocast::set_autocast_cpu_dtype(torch::kBFloat16);
    auto y = net->forward(grid);
    at::autocast::set_cpu_enabled(false);
    at::autocast::clear_cache();
    (y * probe.to(y.scalar_type())).sum().backward();
    return y;
  };
  torch::Tensor y;
  for (auto _ : state) {
    y = run();
    benchmark::DoNotOptimize(y.data_ptr());
  }
  auto grid_ref = grid32.detach().clone().requires_grad_();
  const auto y_ref = reference->forward(grid_ref);
  (y_ref * probe).sum().backward();
  auto relative = [](const torch::Tensor& a, const torch::Tensor& ref) {
    return (a.to(torch::kFloat32) - ref).norm().item<double>() / ref.norm().item<double>();
  };
  state.counters["feature_rel_err"] = relative(y.detach(), y_ref.detach());
  state.counters["grid_grad_rel_err"] = relative(grid.grad(), grid_ref.grad());
  state.SetLabel(std::string(preset_name(preset)) +
                 (bf16       ? "/bf16"
                  : autocast ? "/autocast-bf16"
                  : fp64     ? "/fp64"
                             : "/fp32") +
                 (channels_last ? "/channels-last" : "/contiguous") +
                 " threads=" + std::to_string(torch::get_num_threads()));
}

// NAcF on 2048 slices (encoders included) + loss, fwd+bwd. Reports the bf16 output error against
// fp32 with the same weights as counters (mean and max |Δ| in log-magnitude units).
void BM_NacfFwdBwd(benchmark::State& state) {
  const int64_t preset = state.range(0);
  const bool bf16 = state.range(1) != 0;
  torch::manual_seed(0);
  auto o = options_for(preset, false);
  o.nacf.grid_features = resnet3d_out_features(o.resnet);
  Nacf ref(o.nacf);
  o.nacf.bf16 = bf16;
  Nacf net(o.nacf);
  {
    torch::NoGradGuard g;
    auto dst = net->parameters();
    auto src = ref->parameters();
    for (size_t i = 0; i < dst.size(); ++i) dst[i].copy_(src[i]);
  }
  const auto b = make_batch(kBatch);
  const auto feature = torch::rand({o.nacf.grid_features});
  if (bf16) {
    torch::NoGradGuard g;
    const auto h = nacf_input(o.nacf, feature, b.t, kMaxLen, b.mic, b.src, b.rot);
    const auto d = (net->forward(h) - ref->forward(h)).abs();
    state.counters["mean_abs_err"] = d.mean().item<double>();
    state.counters["max_abs_err"] = d.max().item<double>();
  }
  for (auto _ : state) {
    net->zero_grad();
    const auto h = nacf_input(o.nacf, feature, b.t, kMaxLen, b.mic, b.src, b.rot);
    auto loss = spectral_loss(net->forward(h), b.gt);
    loss.total.backward();
    benchmark::DoNotOptimize(loss.total.item<float>());
  }
  // NAcF's input here is a constant (no ResNet3D in front), so the input gradient of its first
  // layer (the first Linear registered: soundfield.0) is never computed.
  const auto linear = weight_counts<torch::nn::Linear>(*net);
  set_flop_counters(state, double(sum(linear)) * kBatch, double(linear.front()) * kBatch);
  set_label(state, preset, bf16);
}

// The fastest fp32 arithmetic this machine gives LibTorch: one large square matrix product
// (OpenBLAS sgemm), N = range(0). The FLOP counters of the steps above divided by this rate bound
// their time from below: a convolution or an MLP layer is at best a matrix product of its size.
void BM_PeakSgemm(benchmark::State& state) {
  const int64_t n = state.range(0);
  torch::manual_seed(0);
  const auto a = torch::randn({n, n}), b = torch::randn({n, n});
  auto c = torch::empty({n, n});
  for (auto _ : state) {
    torch::mm_out(c, a, b);
    benchmark::DoNotOptimize(c.data_ptr());
  }
  state.counters["gflop_per_s"] =
      benchmark::Counter(2.0 * n * n * n / 1e9, benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel("fp32 threads=" + std::to_string(torch::get_num_threads()));
}

void BM_AdamStep(benchmark::State& state) {
  const int64_t preset = state.range(0);
  AcousticModel m(options_for(preset, false));
  auto params = m->parameters();
  for (auto& p : params) p.mutable_grad() = torch::randn_like(p);
  torch::optim::Adam opt(params, torch::optim::AdamOptions(1e-4).eps(1e-15));
  for (auto _ : state) opt.step();
  int64_t n = 0;
  for (const auto& p : params) n += p.numel();
  state.counters["params"] = static_cast<double>(n);
  set_label(state, preset, false);
}

// One RIR, all 78 frames, network only: ResNet3D (eval) once + NAcF on 78 queries.
void BM_RenderStft(benchmark::State& state) {
  const int64_t preset = state.range(0);
  const bool bf16 = state.range(1) != 0;
  torch::manual_seed(0);
  AcousticModel m(options_for(preset, bf16));
  GridSampler sampler(m->options().grid);
  const auto mic = torch::rand({3}, torch::kFloat64), src = torch::rand({3}, torch::kFloat64),
             rot = torch::rand({3}, torch::kFloat64);
  for (auto _ : state) {
    auto y = m->render_stft(sampler->grid(), mic, src, rot);
    benchmark::DoNotOptimize(y.data_ptr());
  }
  set_label(state, preset, bf16);
}

// Same with the scene feature computed once (many RIRs of one scene): NAcF only.
void BM_RenderStftCachedFeature(benchmark::State& state) {
  const int64_t preset = state.range(0);
  const bool bf16 = state.range(1) != 0;
  torch::manual_seed(0);
  AcousticModel m(options_for(preset, bf16));
  GridSampler sampler(m->options().grid);
  neraf::acoustic::SceneFeatures feature;
  {
    torch::NoGradGuard g;
    m->eval();
    feature = m->scene_features(sampler->grid());
  }
  const auto mic = torch::rand({3}, torch::kFloat64), src = torch::rand({3}, torch::kFloat64),
             rot = torch::rand({3}, torch::kFloat64);
  for (auto _ : state) {
    auto y = m->render_stft_with_feature(feature, mic, src, rot);
    benchmark::DoNotOptimize(y.data_ptr());
  }
  set_label(state, preset, bf16);
}

// cpu preset: many short runs; paper preset: seconds per iteration, so 1 iteration × 3 repetitions.
#define NERAF_CPU(bm, ...) \
  BENCHMARK(bm)->Args({0, __VA_ARGS__})->Unit(benchmark::kMillisecond)->Repetitions(5)
#define NERAF_PAPER(bm, ...)          \
  BENCHMARK(bm)                       \
      ->Args({1, __VA_ARGS__})        \
      ->Unit(benchmark::kMillisecond) \
      ->Iterations(1)                 \
      ->Repetitions(3)

BENCHMARK(BM_PeakSgemm)
    ->Arg(1024)
    ->Arg(2048)
    ->Arg(4096)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5);
NERAF_CPU(BM_AcousticStep, 0);
NERAF_CPU(BM_AcousticStep, 1);
NERAF_CPU(BM_ResNet3dFwdBwd, 0);
NERAF_CPU(BM_ResNet3dLayouts, 0);
NERAF_CPU(BM_ResNet3dLayouts, 1);
NERAF_CPU(BM_ResNet3dLayouts, 2);
NERAF_CPU(BM_ResNet3dLayouts, 3);
NERAF_CPU(BM_ResNet3dLayouts, 4);
NERAF_CPU(BM_ResNet3dLayouts, 6);
NERAF_CPU(BM_ResNet3dLayouts, 8);
NERAF_CPU(BM_NacfFwdBwd, 0);
NERAF_CPU(BM_NacfFwdBwd, 1);
NERAF_CPU(BM_AdamStep, 0);
NERAF_CPU(BM_RenderStft, 0);
NERAF_CPU(BM_RenderStft, 1);
NERAF_CPU(BM_RenderStftCachedFeature, 0);
NERAF_CPU(BM_RenderStftCachedFeature, 1);
// The query path of `neraf render`/`eval --run` (fp32) and of bf16, for the runtime comparison
// (bench/runtime_bench.sh): ~10 ms per call, so several iterations per repetition.
BENCHMARK(BM_RenderStftCachedFeature)->Args({1, 0})->Unit(benchmark::kMillisecond)->Repetitions(5);
BENCHMARK(BM_RenderStftCachedFeature)->Args({1, 1})->Unit(benchmark::kMillisecond)->Repetitions(5);
NERAF_PAPER(BM_AcousticStep, 0);
NERAF_PAPER(BM_AcousticStep, 1);
NERAF_PAPER(BM_ResNet3dFwdBwd, 0);
NERAF_PAPER(BM_ResNet3dLayouts, 0);
NERAF_PAPER(BM_ResNet3dLayouts, 1);
NERAF_PAPER(BM_ResNet3dLayouts, 2);
NERAF_PAPER(BM_ResNet3dLayouts, 3);
NERAF_PAPER(BM_ResNet3dLayouts, 4);
NERAF_PAPER(BM_ResNet3dLayouts, 6);
NERAF_PAPER(BM_ResNet3dLayouts, 8);
NERAF_PAPER(BM_NacfFwdBwd, 0);
NERAF_PAPER(BM_NacfFwdBwd, 1);
NERAF_PAPER(BM_AdamStep, 0);
NERAF_PAPER(BM_RenderStft, 0);
NERAF_PAPER(BM_RenderStft, 1);
NERAF_PAPER(BM_RenderStftCachedFeature, 1);

}  // namespace
}  // namespace neraf::acoustic

int main(int argc, char** argv) {
  // As the neraf program: all cores (LibTorch's default here is 1 thread).
  torch::set_num_threads(static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  return neraf::bench::run_benchmarks(argc, argv);
}
