// One full Nerfacto training step (ray batch → proposal sampling → field → rendering → losses →
// backward → Adam on the three groups), at the paper (Nerfacto default) and cpu preset shapes,
// with fp32 and bf16 MLPs, with and without the proposal-network update (steady state updates
// them on 1 step in 6, so the amortised step is (update + 5·no_update)/6).
// Run each in its own process (the heap left by one benchmark slows the next by up to 30 %):
//   neraf_bench_nerf --benchmark_filter='BM_Step_paper_bf16_update/' --benchmark_repetitions=5 \
//     --benchmark_out=step.json --benchmark_out_format=json
#include <ATen/CPUGeneratorImpl.h>
#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include <memory>

#include "neraf/nerf/nerfacto_model.h"

using namespace neraf::nerf;

namespace {

struct StepBench {
  NerfactoModel model{nullptr};
  std::vector<std::unique_ptr<torch::optim::Adam>> optimizers;
  std::vector<torch::Tensor> params;
  at::Generator gen = at::make_generator<at::CPUGeneratorImpl>(42);
  RayBundle rays;
  torch::Tensor gt;

  StepBench(const std::string& preset, Precision precision, int64_t num_rays) {
    ModelConfig cfg = model_preset(preset);
    cfg.precision = precision;
    const int64_t num_images = 100;
    model = NerfactoModel(cfg, num_images, 42);
    model->train();
    for (auto group :
         {model->proposal_parameters(), model->field_parameters(), model->camera_parameters()}) {
      if (group.empty()) continue;
      optimizers.push_back(
          std::make_unique<torch::optim::Adam>(group, torch::optim::AdamOptions(1e-2).eps(1e-15)));
      for (auto& p : group) params.push_back(p);
    }
    // Rays from inside the unit cube in random directions, like a room seen from within.
    rays.origins = torch::rand({num_rays, 3}, gen) * 1.6 - 0.8;
    auto d = torch::randn({num_rays, 3}, gen);
    rays.directions = d / d.norm(2, 1, true);
    rays.camera_indices = torch::randint(0, num_images, {num_rays}, gen);
    gt = torch::rand({num_rays, 3}, gen);
  }

  void step(bool proposal_grad) {
    for (auto& p : params) p.mutable_grad() = torch::Tensor();
    const ModelOutputs out = model->forward(rays, ForwardOptions{proposal_grad, 1.0, &gen});
    const LossDict l = model->losses(out, gt);
    torch::Tensor total = torch::zeros({});
    for (const auto& [k, v] : l) total = total + v;
    total.backward();
    for (auto& o : optimizers) o->step();
  }
};

void run(benchmark::State& state, const std::string& preset, Precision precision,
         bool proposal_grad) {
  // The benchmark's argument is the thread count (LibTorch's default here is 1, not the cores).
  torch::set_num_threads(static_cast<int>(state.range(0)));
  const int64_t num_rays = 4096;
  StepBench b(preset, precision, num_rays);
  b.step(true);  // warm-up: allocations, oneDNN kernel selection
  b.step(proposal_grad);
  for (auto _ : state) b.step(proposal_grad);
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(num_rays),
                                                benchmark::Counter::kIsIterationInvariantRate);
  state.counters["threads"] = torch::get_num_threads();
}

void BM_Step_paper_fp32_update(benchmark::State& s) { run(s, "paper", Precision::fp32, true); }
void BM_Step_paper_fp32_noupdate(benchmark::State& s) { run(s, "paper", Precision::fp32, false); }
void BM_Step_paper_bf16_update(benchmark::State& s) { run(s, "paper", Precision::bf16, true); }
void BM_Step_paper_bf16_noupdate(benchmark::State& s) { run(s, "paper", Precision::bf16, false); }
void BM_Step_cpu_bf16_update(benchmark::State& s) { run(s, "cpu", Precision::bf16, true); }
void BM_Step_cpu_bf16_noupdate(benchmark::State& s) { run(s, "cpu", Precision::bf16, false); }
void BM_Step_cpu_fp32_update(benchmark::State& s) { run(s, "cpu", Precision::fp32, true); }
void BM_Step_cpu_fp32_noupdate(benchmark::State& s) { run(s, "cpu", Precision::fp32, false); }

}  // namespace

// 2 threads (the machines' cores; LibTorch's default here is 1), wall-clock time.
#define NERAF_STEP_BENCH ->Arg(2)->Unit(benchmark::kMillisecond)->MinTime(2.0)->UseRealTime()
BENCHMARK(BM_Step_paper_fp32_update) NERAF_STEP_BENCH;
BENCHMARK(BM_Step_paper_fp32_noupdate) NERAF_STEP_BENCH;
BENCHMARK(BM_Step_paper_bf16_update) NERAF_STEP_BENCH;
BENCHMARK(BM_Step_paper_bf16_noupdate) NERAF_STEP_BENCH;
BENCHMARK(BM_Step_cpu_bf16_update) NERAF_STEP_BENCH;
BENCHMARK(BM_Step_cpu_bf16_noupdate) NERAF_STEP_BENCH;
BENCHMARK(BM_Step_cpu_fp32_update) NERAF_STEP_BENCH;
BENCHMARK(BM_Step_cpu_fp32_noupdate) NERAF_STEP_BENCH;

// main() (with the malloc tuning of the neraf program) is defined in bench_nerf_ops.cpp.
