// Streaming convolution benchmarks (neraf_stream_*, the C API, no model): one process() call of
// a binaural stream with a 1 s RIR at 48 kHz, in steady state and in a block that crossfades to
// a new RIR. Single-threaded (the stream's worker sleeps while timed; FFTW runs on the calling
// thread). Counter x_realtime: audio duration processed per second of CPU time on one core.
//   neraf_bench_runtime --benchmark_filter=Stream --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "neraf/neraf_rt.h"

namespace {

constexpr int kRate = 48000;
constexpr int kChannels = 2;
constexpr size_t kRirLength = 48000;  // 1 s

// Planar [channels, n]: exponentially decaying noise (RT60 ~ 0.5 s).
std::vector<float> decaying_rir(size_t n, uint32_t seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<float> g(0.0f, 0.1f);
  std::vector<float> h(kChannels * n);
  for (size_t i = 0; i < h.size(); ++i)
    h[i] = g(gen) * static_cast<float>(std::exp(-6.9 * double(i % n) / (0.5 * kRate)));
  return h;
}

std::vector<float> noise(size_t n, uint32_t seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<float> g(0.0f, 0.2f);
  std::vector<float> x(n);
  for (float& v : x) v = g(gen);
  return x;
}

neraf_stream* make_stream(benchmark::State& state, int block, const std::vector<float>& rir) {
  neraf_stream* s = nullptr;
  if (neraf_stream_create(nullptr, kChannels, block, kRirLength, &s) != NERAF_OK ||
      neraf_stream_set_rir(s, rir.data(), kChannels, kRirLength) != NERAF_OK ||
      neraf_stream_wait(s, 60000) != NERAF_OK) {
    state.SkipWithError(neraf_last_error());
    neraf_stream_free(s);
    return nullptr;
  }
  return s;
}

// Argument: block size. Steady state: the same RIR throughout, input noise cycling over 1 s.
void BM_StreamBinaural1s(benchmark::State& state) {
  const int block = static_cast<int>(state.range(0));
  const std::vector<float> rir = decaying_rir(kRirLength, 1);
  const std::vector<float> x = noise(size_t(kRate / block) * size_t(block), 2);
  std::vector<float> out(size_t(kChannels) * size_t(block));
  neraf_stream* s = make_stream(state, block, rir);
  if (!s) return;
  size_t t = 0;
  // One full pass first: the FDL fills and every partition is in use from the first timed call.
  for (size_t i = 0; i < kRirLength / size_t(block) + 2; ++i) {
    neraf_stream_process(s, x.data() + t, out.data());
    t = t + 2 * size_t(block) > x.size() ? 0 : t + size_t(block);
  }
  for (auto _ : state) {
    neraf_stream_process(s, x.data() + t, out.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
    t = t + 2 * size_t(block) > x.size() ? 0 : t + size_t(block);
  }
  const double block_seconds = double(block) / kRate;
  state.counters["x_realtime"] =
      benchmark::Counter(block_seconds * double(state.iterations()), benchmark::Counter::kIsRate);
  neraf_stream_free(s);
}
BENCHMARK(BM_StreamBinaural1s)->Arg(64)->Arg(128)->Arg(256)->Arg(512)->Arg(1024)
    ->Unit(benchmark::kMicrosecond)->Threads(1);

// A block that picks up a new RIR and crossfades (two RIRs rendered): set_rir and the wait for
// the worker are outside the timed region (manual timing of the process() call alone).
void BM_StreamBinaural1sCrossfade(benchmark::State& state) {
  const int block = static_cast<int>(state.range(0));
  const std::vector<float> rir[2] = {decaying_rir(kRirLength, 1), decaying_rir(kRirLength, 3)};
  const std::vector<float> x = noise(size_t(kRate / block) * size_t(block), 2);
  std::vector<float> out(size_t(kChannels) * size_t(block));
  neraf_stream* s = make_stream(state, block, rir[0]);
  if (!s) return;
  size_t t = 0;
  for (size_t i = 0; i < kRirLength / size_t(block) + 2; ++i) {
    neraf_stream_process(s, x.data() + t, out.data());
    t = t + 2 * size_t(block) > x.size() ? 0 : t + size_t(block);
  }
  int next = 1;
  for (auto _ : state) {
    if (neraf_stream_set_rir(s, rir[next].data(), kChannels, kRirLength) != NERAF_OK ||
        neraf_stream_wait(s, 60000) != NERAF_OK) {
      state.SkipWithError(neraf_last_error());
      break;
    }
    next = 1 - next;
    const auto t0 = std::chrono::steady_clock::now();
    neraf_stream_process(s, x.data() + t, out.data());
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
    const auto t1 = std::chrono::steady_clock::now();
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    t = t + 2 * size_t(block) > x.size() ? 0 : t + size_t(block);
  }
  const double block_seconds = double(block) / kRate;
  state.counters["x_realtime"] =
      benchmark::Counter(block_seconds * double(state.iterations()), benchmark::Counter::kIsRate);
  neraf_stream_free(s);
}
BENCHMARK(BM_StreamBinaural1sCrossfade)->Arg(256)->UseManualTime()->Unit(benchmark::kMicrosecond)
    ->Threads(1);

}  // namespace

// main: BENCHMARK_MAIN() in bench/bench_runtime.cpp (one per executable).
