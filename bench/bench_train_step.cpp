// The real joint training step (issue 14 §4), as `neraf train` runs it: the trainer of
// train/trainer.h on a dataset from disk, audio from step 0, at the cpu and paper presets.
//   vision  the radiance field alone (--modality vision)
//   zeros   joint with an all-zero grid (--grid zeros): vision + ResNet3D + NAcF, no grid update
//   joint   joint with the sampled grid: the above plus the grid update, whose cells are queried
//           through the radiance field with autograd and back-propagated into it
// so joint − zeros is the grid update's cost and zeros − vision the acoustic field's.
//   NERAF_BENCH_DATA=DIR neraf_bench_train --benchmark_filter='BM_TrainStep/cpu_joint'
// DIR: a SoundSpaces-layout dataset (`neraf synth --preset demo --out DIR`); bench/train_step.sh
// makes one and runs every case in its own process (the heap left by one slows the next).
#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include <cstdlib>
#include <string>

#include "bench_main.h"
#include "neraf/data/image_set.h"
#include "neraf/data/rir_set.h"
#include "neraf/infer/train_config.h"
#include "neraf/train/trainer.h"

using namespace neraf;

namespace {

void run(benchmark::State& state, const std::string& preset, const std::string& mode) {
  const char* dir = std::getenv("NERAF_BENCH_DATA");
  if (!dir) {
    state.SkipWithError("set NERAF_BENCH_DATA to a dataset (neraf synth --preset demo --out DIR)");
    return;
  }
  // The benchmark's argument is the thread count (LibTorch's default here is 1, not the cores).
  torch::set_num_threads(static_cast<int>(state.range(0)));
  infer::TrainFlags flags;
  flags.preset = preset;
  flags.modality = mode == "vision" ? infer::Modality::vision : infer::Modality::joint;
  flags.steps = 100000;         // a long run's learning rates; only a few steps are taken
  flags.audio_start_step = -1;  // audio from the first step
  flags.grid = mode == "zeros" ? "zeros" : "sampled";
  const infer::TrainConfig cfg = infer::resolve_train_config(flags);
  data::ImageLoadOptions image_load;
  image_load.progress = false;
  const data::ImageSet images = data::load_transforms_json(dir, image_load);
  data::RirLoadOptions rir_load;
  rir_load.progress = false;
  const data::RirSet rirs = data::load_rir_set(dir, rir_load);
  auto trainer = train::make_trainer(cfg, &images, torch::kCPU, &rirs);
  for (int i = 0; i < 2; ++i) trainer->step();  // warm-up: allocations, oneDNN kernel selection
  for (auto _ : state) trainer->step();
  state.counters["rays"] = static_cast<double>(cfg.rays_per_batch);
  state.counters["audio_slices"] =
      mode == "vision" ? 0.0 : static_cast<double>(cfg.audio.batch_size);
  state.counters["grid_cells_per_step"] =
      mode == "joint" ? static_cast<double>(cfg.audio.cells_per_update) : 0.0;
  state.counters["threads"] = torch::get_num_threads();
}

}  // namespace

// 2 threads (the machines' cores), wall-clock time. The paper preset's step takes seconds.
#define NERAF_TRAIN_STEP(preset, mode, seconds)           \
  BENCHMARK_CAPTURE(run, preset##_##mode, #preset, #mode) \
      ->Name("BM_TrainStep/" #preset "_" #mode)           \
      ->Arg(2)                                            \
      ->Unit(benchmark::kMillisecond)                     \
      ->MinTime(seconds)                                  \
      ->UseRealTime()
NERAF_TRAIN_STEP(cpu, vision, 5.0);
NERAF_TRAIN_STEP(cpu, zeros, 5.0);
NERAF_TRAIN_STEP(cpu, joint, 5.0);
NERAF_TRAIN_STEP(paper, vision, 10.0);
NERAF_TRAIN_STEP(paper, zeros, 20.0);
NERAF_TRAIN_STEP(paper, joint, 20.0);

int main(int argc, char** argv) { return neraf::bench::run_benchmarks(argc, argv); }
