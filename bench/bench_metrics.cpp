// Evaluation cost: one RIR comparison (what `neraf eval` runs per test RIR) and one image's SSIM.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "neraf/metrics/image_metrics.h"
#include "neraf/metrics/rir_errors.h"

namespace {

using neraf::metrics::Variant;

std::vector<float> decaying_noise(double t60, double fs, size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  std::vector<float> h(n);
  for (size_t i = 0; i < n; ++i) h[i] = u(rng) * float(std::pow(10.0, -3.0 * (i / fs) / t60));
  return h;
}

// SoundSpaces: binaural, 22.05 kHz, 101 frames · 128 = 12928 samples (apartment_1's max_len).
void BM_CompareRirs_SoundSpaces(benchmark::State& state) {
  const double fs = 22050;
  const size_t n = 101 * 128;
  const neraf::io::AudioBuffer gt{int(fs),
                                  {decaying_noise(0.5, fs, n, 1), decaying_noise(0.5, fs, n, 2)}};
  const neraf::io::AudioBuffer pred{
      int(fs), {decaying_noise(0.45, fs, n - 128, 3), decaying_noise(0.55, fs, n - 128, 4)}};
  for (auto _ : state) {
    benchmark::DoNotOptimize(neraf::metrics::compare_rirs(pred, gt, Variant::soundspaces));
  }
}
BENCHMARK(BM_CompareRirs_SoundSpaces)->Unit(benchmark::kMillisecond);

// RAF: mono, 48 kHz, 15360 samples.
void BM_CompareRirs_Raf(benchmark::State& state) {
  const double fs = 48000;
  const neraf::io::AudioBuffer gt{int(fs), {decaying_noise(0.5, fs, 15360, 1)}};
  const neraf::io::AudioBuffer pred{int(fs), {decaying_noise(0.45, fs, 15104, 3)}};
  for (auto _ : state) {
    benchmark::DoNotOptimize(neraf::metrics::compare_rirs(pred, gt, Variant::raf));
  }
}
BENCHMARK(BM_CompareRirs_Raf)->Unit(benchmark::kMillisecond);

// SoundSpaces eval views are 512×512 RGB.
void BM_Ssim_512(benchmark::State& state) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  neraf::metrics::ImageRGB a(512, 512), b(512, 512);
  for (float& v : a.pixels) v = u(rng);
  for (float& v : b.pixels) v = u(rng);
  for (auto _ : state) benchmark::DoNotOptimize(neraf::metrics::ssim(a.view(), b.view()));
}
BENCHMARK(BM_Ssim_512)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
