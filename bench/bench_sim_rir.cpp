// Time per simulated RIR: a 'demo'-like furnished room (5 × 3 × 4 m, three boxes, image order 8),
// binaural at 44.1 kHz (SoundSpaces) and mono at 48 kHz (RAF), plus the per-scene setup cost.
// Run: build/neraf_bench_sim --benchmark_filter=Rir
#include <benchmark/benchmark.h>

#include "neraf/sim/hrtf.h"
#include "neraf/sim/rir_simulator.h"

namespace neraf::sim {
namespace {

Scene demo_like_room(double length_s) {
  Scene s;
  s.size = {5, 3, 4};
  Material wall, floor, ceiling, wood, sofa;
  wall.absorption = {0.10, 0.08, 0.06, 0.05, 0.05, 0.05, 0.05};
  floor.absorption = {0.05, 0.07, 0.10, 0.15, 0.25, 0.30, 0.35};    // carpet-ish
  ceiling.absorption = {0.30, 0.35, 0.50, 0.60, 0.60, 0.55, 0.50};  // acoustic tiles
  wood.absorption = {0.15, 0.11, 0.10, 0.07, 0.06, 0.07, 0.07};
  sofa.absorption = {0.20, 0.35, 0.50, 0.60, 0.65, 0.65, 0.60};
  sofa.scattering = 0.4;
  s.materials = {
      {"wall", wall}, {"floor", floor}, {"ceiling", ceiling}, {"wood", wood}, {"sofa", sofa}};
  s.furniture = {{{1.2, 0.4, 1.0}, {1.8, 0.8, 0.9}, 0, "sofa"},
                 {{3.6, 0.375, 2.5}, {1.2, 0.75, 0.8}, 20, "wood"},
                 {{4.6, 0.9, 0.5}, {0.6, 1.8, 0.4}, 0, "wood"}};
  s.acoustics.max_order = 8;
  s.acoustics.rir_length_s = length_s;
  return s;
}

const Hrtf& kemar44() {
  static const Hrtf h(44100);
  return h;
}

// Poses cycle over a small grid so that occlusion, reflections and the HRIR lookup vary.
void render_loop(benchmark::State& state, const RirSimulator& sim) {
  const Source src{{2.5, 1.2, 3.2}, 30, "omni"};
  int i = 0;
  for (auto _ : state) {
    const Vec3 mic{0.6 + 0.45 * (i % 9), 1.5, 0.6 + 0.35 * ((i / 9) % 8)};
    auto h = sim.render(src, mic, 90.0 * (i % 4));
    benchmark::DoNotOptimize(h.data());
    ++i;
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_RirBinaural44k(benchmark::State& state) {
  RirSimOptions o;
  o.seed = 1;
  RirSimulator sim(demo_like_room(1.0), 44100, &kemar44(), o);
  render_loop(state, sim);
}
BENCHMARK(BM_RirBinaural44k)->Unit(benchmark::kMillisecond);

void BM_RirMono48k(benchmark::State& state) {
  RirSimOptions o;
  o.binaural = false;
  RirSimulator sim(demo_like_room(1.5), 48000, nullptr, o);
  render_loop(state, sim);
}
BENCHMARK(BM_RirMono48k)->Unit(benchmark::kMillisecond);

void BM_RirSimulatorSetupBinaural44k(benchmark::State& state) {
  const Scene s = demo_like_room(1.0);
  kemar44();
  for (auto _ : state) {
    RirSimulator sim(s, 44100, &kemar44(), {});
    benchmark::DoNotOptimize(&sim);
  }
}
BENCHMARK(BM_RirSimulatorSetupBinaural44k)->Unit(benchmark::kMillisecond);

void BM_HrtfLoad44k(benchmark::State& state) {
  for (auto _ : state) {
    Hrtf h(44100);
    benchmark::DoNotOptimize(&h);
  }
}
BENCHMARK(BM_HrtfLoad44k)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace neraf::sim
BENCHMARK_MAIN();  // the one main of neraf_bench_sim (other bench_sim*.cpp files must not add one)
