// Acoustic-branch benchmarks: one training step (ResNet3D fwd+bwd on the grid + NAcF fwd+bwd on
// 2048 slices + SC+SLMSE loss), its parts, the Adam step, and render_stft latency for one RIR.
// Shapes: SoundSpaces (C = 2, F = 257, max_len = 78 frames). Presets cpu (32³ grid, small ResNet,
// NAcF 5×512) and paper (128³, ResNet3D-50/layer3, NAcF 1187→5096→…→512), fp32 and bf16 NAcF trunk.
//
//   build-x/neraf_bench_acoustic                      # writes bench/results/acoustic.json
//   build-x/neraf_bench_acoustic --benchmark_filter=cpu
// Without --benchmark_out the JSON goes to <repo>/bench/results/acoustic.json.
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <torch/torch.h>

#include <algorithm>
#include <string>
#include <thread>
#include <vector>

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
  set_label(state, preset, false);
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
  set_label(state, preset, bf16);
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

NERAF_CPU(BM_AcousticStep, 0);
NERAF_CPU(BM_AcousticStep, 1);
NERAF_CPU(BM_ResNet3dFwdBwd, 0);
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
NERAF_PAPER(BM_NacfFwdBwd, 0);
NERAF_PAPER(BM_NacfFwdBwd, 1);
NERAF_PAPER(BM_AdamStep, 0);
NERAF_PAPER(BM_RenderStft, 0);
NERAF_PAPER(BM_RenderStft, 1);
NERAF_PAPER(BM_RenderStftCachedFeature, 1);

}  // namespace
}  // namespace neraf::acoustic

int main(int argc, char** argv) {
  // As the neraf program: all cores (LibTorch's default here is 1 thread) and no mmap churn.
  torch::set_num_threads(static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  std::vector<char*> args(argv, argv + argc);
  bool has_out = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]).rfind("--benchmark_out=", 0) == 0) has_out = true;
  }
  std::string out =
      std::string("--benchmark_out=") + NERAF_ASSETS_DIR + "/../bench/results/acoustic.json";
  std::string fmt = "--benchmark_out_format=json";
  if (!has_out) {
    args.push_back(out.data());
    args.push_back(fmt.data());
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
