// DSP benchmarks: the STFT features, Griffin-Lim (the metric path of every evaluated RIR) and the
// auralization convolution. Inputs are random but seeded.
//   neraf_bench_dsp --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>

#include "bench_main.h"
#include "neraf/dsp/convolve.h"
#include "neraf/dsp/griffin_lim.h"
#include "neraf/dsp/stft.h"

namespace {

using neraf::dsp::Matrix;
using neraf::dsp::StftParams;

std::vector<float> random_signal(size_t n, uint32_t seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<float> g(0.0f, 0.2f);
  std::vector<float> x(n);
  for (float& v : x) v = g(gen);
  return x;
}

// A plausible RIR magnitude: the STFT magnitude of exponentially decaying noise.
Matrix rir_magnitude(const StftParams& p, size_t n, double fs, uint32_t seed) {
  auto x = random_signal(n, seed);
  for (size_t i = 0; i < n; ++i) x[i] *= static_cast<float>(std::exp(-double(i) / fs / 0.1));
  return neraf::dsp::magnitude(neraf::dsp::stft(x, p));
}

void BM_StftRaf(benchmark::State& state) {  // 0.32 s at 48 kHz -> [513, 61]
  const auto x = random_signal(15360, 1);
  for (auto _ : state) benchmark::DoNotOptimize(neraf::dsp::stft(x, StftParams::raf()));
}
BENCHMARK(BM_StftRaf)->Unit(benchmark::kMicrosecond);

void BM_StftSoundSpaces(benchmark::State& state) {  // 1 s at 22.05 kHz -> [257, 173]
  const auto x = random_signal(22050, 2);
  for (auto _ : state) benchmark::DoNotOptimize(neraf::dsp::stft(x, StftParams::soundspaces()));
}
BENCHMARK(BM_StftSoundSpaces)->Unit(benchmark::kMicrosecond);

void BM_IstftRaf(benchmark::State& state) {
  const auto S = neraf::dsp::stft(random_signal(15360, 3), StftParams::raf());
  for (auto _ : state) benchmark::DoNotOptimize(neraf::dsp::istft(S, StftParams::raf()));
}
BENCHMARK(BM_IstftRaf)->Unit(benchmark::kMicrosecond);

// Argument: GriffinLimOptions::threads (0 automatic: serial when the cores are already busy;
// 1 serial; 2 forced two threads).
void BM_GriffinLimRaf(benchmark::State& state) {  // 32 iterations on [513, 60]
  // 60 frames as in the RAF evaluation (the GT STFT truncated to max_len).
  const Matrix full = rir_magnitude(StftParams::raf(), 15360, 48000.0, 4);
  Matrix S(513, 60);
  for (int f = 0; f < 513; ++f) {
    for (int t = 0; t < 60; ++t) S(f, t) = full(f, t);
  }
  neraf::dsp::GriffinLimOptions o;
  o.seed = 1;
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(neraf::dsp::griffin_lim(S, StftParams::raf(), o));
}
BENCHMARK(BM_GriffinLimRaf)
    ->ArgName("threads")
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond);

void BM_GriffinLimSoundSpacesBinaural(benchmark::State& state) {  // 32 iterations on [2, 257, 100]
  std::vector<Matrix> S;
  for (uint32_t c = 0; c < 2; ++c) {
    const Matrix full = rir_magnitude(StftParams::soundspaces(), 128 * 99, 22050.0, 5 + c);
    S.push_back(full);
  }
  neraf::dsp::GriffinLimOptions o;
  o.seed = 1;
  o.threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(neraf::dsp::griffin_lim(S, StftParams::soundspaces(), o));
  }
}
BENCHMARK(BM_GriffinLimSoundSpacesBinaural)
    ->ArgName("threads")
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond);

void BM_ConvolveRir1sAudio10s(benchmark::State& state) {  // 48 kHz
  const auto rir = random_signal(48000, 7);
  const auto audio = random_signal(480000, 8);
  for (auto _ : state) benchmark::DoNotOptimize(neraf::dsp::fft_convolve(audio, rir));
}
BENCHMARK(BM_ConvolveRir1sAudio10s)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) { return neraf::bench::run_benchmarks(argc, argv); }
