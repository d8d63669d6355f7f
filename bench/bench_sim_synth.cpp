// `neraf synth` speed: one photo, the whole demo preset, and a SoundSpaces-sized scene (~10k
// binaural RIRs, bench/scenes/soundspaces_10k.json). Targets on 2 cores: demo < 1 min, 10k < 10
// min. The 10k case takes minutes, so it is only registered when asked for:
//   NERAF_BENCH_LARGE=1 neraf_bench_sim --benchmark_filter=Synth10k
// (part of neraf_bench_sim, whose main() is in bench_sim_rir.cpp).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "neraf/sim/cameras.h"
#include "neraf/sim/image_renderer.h"
#include "neraf/sim/presets.h"
#include "neraf/sim/scene_json.h"
#include "neraf/sim/seeded_random.h"
#include "neraf/sim/synthesize.h"

namespace {

using namespace neraf::sim;
namespace fs = std::filesystem;

void BM_RenderImageDemo(benchmark::State& state) {
  Scene s = preset_scene("demo");
  s.cameras.width = s.cameras.height = static_cast<int>(state.range(0));
  const auto cams = place_cameras(s, 8, 1);
  const ImageRenderer renderer(s);
  size_t i = 0;
  for (auto _ : state) {
    auto img = renderer.render(cams[i++ % cams.size()], s.cameras.supersampling);
    benchmark::DoNotOptimize(img.pixels.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderImageDemo)->Arg(96)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime();

void synth_loop(benchmark::State& state, const Scene& scene, const std::string& layout) {
  const fs::path out =
      fs::temp_directory_path() / ("neraf_bench_synth_" + std::to_string(::getpid()));
  int64_t rirs = 0;
  for (auto _ : state) {
    state.PauseTiming();
    fs::remove_all(out);
    state.ResumeTiming();
    SynthOptions o;
    o.layout = layout;
    o.out_dir = out.string();
    o.progress = false;
    const SynthSummary sum = synthesize(scene, o);
    rirs += sum.num_rirs;
    state.counters["rirs"] = double(sum.num_rirs);
    state.counters["images"] = double(sum.num_train_images + sum.num_eval_images);
    state.counters["rir_s"] = sum.rir_seconds;
    state.counters["image_s"] = sum.image_seconds;
  }
  state.SetItemsProcessed(rirs);
  fs::remove_all(out);
}

void BM_SynthDemoSoundSpaces(benchmark::State& state) {
  synth_loop(state, preset_scene("demo"), "soundspaces");
}
BENCHMARK(BM_SynthDemoSoundSpaces)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(3);

void BM_SynthDemoRaf(benchmark::State& state) { synth_loop(state, preset_scene("demo"), "raf"); }
BENCHMARK(BM_SynthDemoRaf)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(3);

void BM_Synth10kSoundSpaces(benchmark::State& state) {
  const std::string path = std::string(NERAF_ASSETS_DIR) + "/../bench/scenes/soundspaces_10k.json";
  synth_loop(state, load_scene(path), "soundspaces");
}
// Registered only when NERAF_BENCH_LARGE is set (minutes per run).
const bool kRegistered10k = [] {
  if (!std::getenv("NERAF_BENCH_LARGE")) return false;
  benchmark::RegisterBenchmark("BM_Synth10kSoundSpaces", BM_Synth10kSoundSpaces)
      ->Unit(benchmark::kSecond)
      ->UseRealTime()
      ->Iterations(1);
  return true;
}();

}  // namespace
