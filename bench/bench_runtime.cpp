// neraf_rt benchmarks through the C API of the shared library, on synthetic models with random
// weights (model_file.h writes them) of the two presets' sizes, SoundSpaces audio (C = 2, F = 257,
// T = 78 frames, n_fft 512, hop 128):
//   cpu    inputs 185 (relative geometry), trunk 5 × 512
//   paper  inputs 163, trunk 5096 → 2048 → 1024 → 1024 → 512
// LogStft: the network part of one RIR (pose → calibrated log-STFT); Rir: the whole RIR with
// 32 Griffin-Lim iterations (threads: 0 = automatic, one per channel; 1 = the caller only).
// bf16: the model stored in bfloat16, whose trunk runs on AMX tiles where the CPU has them.
//   neraf_bench_runtime --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// BLAS threads follow OpenBLAS's own settings (OPENBLAS_NUM_THREADS / OMP_NUM_THREADS).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "neraf/neraf_rt.h"
#include "neraf/runtime/model_file.h"

namespace {

namespace fs = std::filesystem;

neraf::rt::DenseLayer random_layer(int64_t in, int64_t out, std::mt19937& gen) {
  neraf::rt::DenseLayer l;
  l.in = in;
  l.out = out;
  std::uniform_real_distribution<float> u(-1.0f / std::sqrt(float(in)),
                                          1.0f / std::sqrt(float(in)));
  l.weight.resize(size_t(in * out));
  l.bias.resize(size_t(out));
  for (float& w : l.weight) w = u(gen);
  for (float& b : l.bias) b = u(gen);
  return l;
}

neraf::rt::ModelData synthetic_model(bool paper, bool bf16) {
  std::mt19937 gen(paper ? 2 : 1);
  neraf::rt::ModelData m;
  m.neraf_version = "bench";
  m.max_len = 78;
  m.box_min = {-1, 0, -1};
  m.box_max = {5, 3, 6};
  m.extent_m = {6, 3, 7};
  m.relative_geometry = !paper;
  m.position_max_freq_exp = paper ? 8.0 : 1.0;
  const std::vector<int64_t> trunk =
      paper ? std::vector<int64_t>{5096, 2048, 1024, 1024, 512} : std::vector<int64_t>(5, 512);
  int64_t in = m.input_dim();
  for (int64_t w : trunk) {
    m.trunk.push_back(random_layer(in, w, gen));
    in = w;
  }
  for (int c = 0; c < m.channels; ++c) m.heads.push_back(random_layer(in, m.n_freq, gen));
  std::uniform_real_distribution<float> g(0.5f, 2.0f);
  m.calibration.resize(size_t(m.channels) * m.n_freq * m.max_len);
  for (float& v : m.calibration) v = g(gen);
  m.bf16_storage = bf16;
  return m;
}

// Loaded once per preset and precision for the whole program.
struct Loaded {
  neraf_model* model = nullptr;
  neraf_model_info info{};
};

const Loaded& loaded(bool paper, bool bf16) {
  static Loaded cache[2][2];
  Loaded& l = cache[paper][bf16];
  if (!l.model) {
    std::string t = (fs::temp_directory_path() / "neraf_bench_rt_XXXXXX").string();
    const fs::path dir = ::mkdtemp(t.data());
    const std::string path = (dir / "model.nrf").string();
    neraf::rt::write_model_file(path, synthetic_model(paper, bf16));
    if (neraf_model_load(path.c_str(), &l.model) != NERAF_OK) {
      std::fprintf(stderr, "%s\n", neraf_last_error());
      std::abort();
    }
    neraf_model_get_info(l.model, &l.info);
    fs::remove_all(dir);
  }
  return l;
}

// Poses along a line through the box, so consecutive queries differ.
neraf_pose pose_at(int64_t i) {
  const double a = double(i % 97) / 97.0;
  return {{0.5 + 3 * a, 1.2, 0.5 + 4 * a}, {4.0 - 2 * a, 1.5, 1.0 + a}, 15.0 * double(i % 24)};
}

void BM_LogStft(benchmark::State& state) {
  const Loaded& l = loaded(state.range(0) == 1, state.range(1) == 1);
  neraf_workspace* ws = nullptr;
  neraf_workspace_create(l.model, &ws);
  std::vector<float> out(size_t(l.info.channels) * l.info.n_freq * l.info.n_frames);
  int64_t i = 0;
  for (auto _ : state) {
    const neraf_pose p = pose_at(i++);
    if (neraf_query_log_stft(l.model, ws, &p, 0, out.data(), out.size()) != NERAF_OK)
      state.SkipWithError(neraf_last_error());
    benchmark::DoNotOptimize(out.data());
  }
  state.SetLabel(neraf_model_compute(l.model));  // float32, bfloat16-amx or bfloat16-avx512
  neraf_workspace_free(ws);
}
BENCHMARK(BM_LogStft)
    ->ArgNames({"paper", "bf16"})
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Rir(benchmark::State& state) {
  const Loaded& l = loaded(state.range(0) == 1, state.range(1) == 1);
  neraf_workspace* ws = nullptr;
  neraf_workspace_create(l.model, &ws);
  neraf_workspace_set_threads(ws, int(state.range(2)));
  std::vector<float> out(size_t(l.info.channels) * l.info.rir_length);
  int64_t i = 0;
  for (auto _ : state) {
    const neraf_pose p = pose_at(i++);
    if (neraf_query_rir(l.model, ws, &p, 0, out.data(), out.size()) != NERAF_OK)
      state.SkipWithError(neraf_last_error());
    benchmark::DoNotOptimize(out.data());
  }
  state.SetLabel(neraf_model_compute(l.model));  // float32, bfloat16-amx or bfloat16-avx512
  neraf_workspace_free(ws);
}
BENCHMARK(BM_Rir)
    ->ArgNames({"paper", "bf16", "threads"})
    ->Args({0, 0, 0})
    ->Args({0, 0, 1})
    ->Args({0, 1, 0})
    ->Args({1, 0, 0})
    ->Args({1, 1, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Load(benchmark::State& state) {  // read, verify and prepare a model file (float32)
  const bool paper = state.range(0) == 1;
  std::string t = (fs::temp_directory_path() / "neraf_bench_rt_XXXXXX").string();
  const fs::path dir = ::mkdtemp(t.data());
  const std::string path = (dir / "model.nrf").string();
  neraf::rt::write_model_file(path, synthetic_model(paper, false));
  // The file sizes of the preset (they depend on the shapes only): fp32 and bf16 storage.
  const std::string half = (dir / "model_bf16.nrf").string();
  neraf::rt::write_model_file(half, synthetic_model(paper, true));
  state.counters["fp32_file_MB"] = double(fs::file_size(path)) / 1e6;
  state.counters["bf16_file_MB"] = double(fs::file_size(half)) / 1e6;
  for (auto _ : state) {
    neraf_model* m = nullptr;
    if (neraf_model_load(path.c_str(), &m) != NERAF_OK) state.SkipWithError(neraf_last_error());
    neraf_model_free(m);
  }
  fs::remove_all(dir);
}
BENCHMARK(BM_Load)->ArgName("paper")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
