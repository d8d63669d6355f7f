// Data-stage speed: the per-step training gather of (rir, frame) slices from the memory-mapped
// feature cache, and whole-RIR feature reads. The cache is SoundSpaces-shaped (2 × 257 × 100
// per RIR) and filled synthetically (FeatureCache::build with a cheap compute), so the numbers
// measure the copy path, not STFTs.
#include <benchmark/benchmark.h>
#include <stdlib.h>
#include <torch/torch.h>

#include <filesystem>
#include <memory>

#include "neraf/data/feature_cache.h"
#include "neraf/data/rir_set.h"

namespace fs = std::filesystem;
using namespace neraf;

namespace {

struct Fixture {
  std::string dir;
  data::RirSet set;

  Fixture(int64_t n_rirs, bool half) {
    std::string tmpl = (fs::temp_directory_path() / "neraf_bench_data_XXXXXX").string();
    dir = mkdtemp(tmpl.data());
    data::FeatureCacheSpec spec;
    spec.key = half ? "bench-half" : "bench-float";
    spec.layout = "soundspaces";
    spec.n_rirs = n_rirs;
    spec.channels = 2;
    spec.n_freq = 257;
    spec.max_len = 100;
    spec.half = half;
    const int64_t per = spec.max_len * spec.channels * spec.n_freq;
    auto cache = data::FeatureCache::build(
        dir + "/cache.bin", spec,
        [per](int64_t i, float* out) {
          for (int64_t k = 0; k < per; ++k) out[k] = static_cast<float>((i * 31 + k) % 997) * 1e-3f;
          return int64_t(100);
        },
        /*progress=*/false);
    set.channels = 2;
    set.n_freq = 257;
    set.max_len = 100;
    set.rirs.resize(static_cast<size_t>(n_rirs));
    set.cache_ = cache;
  }
  ~Fixture() { fs::remove_all(dir); }
};

Fixture& fixture(bool half) {
  // 2000 RIRs × 2 × 257 × 100 floats = 411 MB (float32) / 206 MB (float16): larger than the
  // caches, smaller than RAM, like a mid-size scene whose cache sits in the page cache.
  static Fixture f32(2000, false);
  static Fixture f16(2000, true);
  return half ? f16 : f32;
}

void BM_Gather(benchmark::State& state) {
  Fixture& f = fixture(state.range(1) != 0);
  const int64_t b = state.range(0);
  torch::manual_seed(0);
  torch::Tensor out = torch::empty({b, 2, 257});
  for (auto _ : state) {
    state.PauseTiming();
    const torch::Tensor rir = torch::randint(0, f.set.size(), {b}, torch::kInt64);
    const torch::Tensor frame = torch::randint(0, f.set.max_len, {b}, torch::kInt64);
    state.ResumeTiming();
    f.set.gather_into(rir, frame, out);
    benchmark::DoNotOptimize(out.data_ptr<float>());
  }
  state.SetItemsProcessed(state.iterations() * b);
  state.SetBytesProcessed(state.iterations() * b * 2 * 257 * 4);
}
BENCHMARK(BM_Gather)
    ->Args({2048, 0})
    ->Args({2048, 1})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

void BM_Features(benchmark::State& state) {
  Fixture& f = fixture(false);
  int64_t i = 0;
  for (auto _ : state) {
    torch::Tensor x = f.set.features(i);
    benchmark::DoNotOptimize(x.data_ptr<float>());
    i = (i + 37) % f.set.size();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Features)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
