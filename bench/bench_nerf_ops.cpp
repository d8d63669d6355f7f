// Benchmarks of the radiance field's encoding ops at Nerfacto shapes (radiance-field-and-cpu.md
// §3.4): hash grid forward / backward / both, the LibTorch-ops reference, the proposal grids and
// the SH encoding.
//
// NOTE: this file defines main() for the whole neraf_bench_nerf executable (it tunes glibc malloc
// first, as the neraf program does); other bench/bench_nerf*.cpp files must not define their own.
//
// Run: neraf_bench_nerf --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//        --benchmark_out_format=json --benchmark_out=bench/results/nerf_ops.json
#include <benchmark/benchmark.h>
#include <torch/torch.h>

#include <cstdint>

#include "bench_main.h"
#include "neraf/nerf/hash_grid.h"
#include "neraf/nerf/sh_encoding.h"

namespace neraf::nerf {
namespace {

constexpr int64_t kRays = 4096;

// Sample points of `rays` random rays, `samples` each, as they arrive in the contracted unit cube
// (ray-coherent, like the real input): origins near the centre, steps of up to half the cube.
torch::Tensor ray_points(int64_t rays, int64_t samples, uint64_t seed) {
  torch::manual_seed(seed);
  const torch::Tensor origin = torch::rand({rays, 1, 3}) * 0.4 + 0.3;
  torch::Tensor dir = torch::randn({rays, 1, 3});
  dir = dir / dir.norm(2, 2, true);
  const torch::Tensor t = torch::linspace(0.0, 0.5, samples).reshape({1, samples, 1});
  return (origin + dir * t).clamp(0.0, 1.0).reshape({rays * samples, 3}).contiguous();
}

HashGridConfig main_grid() { return {}; }
HashGridConfig proposal_grid(int max_res) { return {5, 2, 17, 16, max_res}; }

struct GridCase {
  HashGridLayout layout;
  torch::Tensor x, table, upstream;
};

GridCase make_case(const HashGridConfig& cfg, int64_t samples_per_ray) {
  GridCase c;
  c.layout = HashGridLayout::make(cfg);
  c.x = ray_points(kRays, samples_per_ray, 7);
  c.table = (torch::rand({c.layout.total_entries, c.layout.features()}) * 2e-4 - 1e-4);
  c.upstream = torch::randn({c.x.size(0), c.layout.output_dim()});
  return c;
}

void set_threads(benchmark::State& state) {
  torch::set_num_threads(static_cast<int>(state.range(0)));
}

void finish(benchmark::State& state, int64_t points) {
  state.SetItemsProcessed(state.iterations() * points);
  state.counters["points"] = static_cast<double>(points);
}

// ---- hash grid through the autograd op (what training runs) ---------------------------------

void hash_fwd_bwd(benchmark::State& state, const HashGridConfig& cfg, int64_t spr, bool grad_x) {
  set_threads(state);
  GridCase c = make_case(cfg, spr);
  torch::Tensor table = c.table.clone().set_requires_grad(true);
  torch::Tensor x = c.x.clone().set_requires_grad(grad_x);
  for (auto _ : state) {
    table.mutable_grad().reset();
    if (grad_x) x.mutable_grad().reset();
    torch::Tensor out = hash_grid_encode(x, table, c.layout);
    out.backward(c.upstream);
    benchmark::DoNotOptimize(table.grad().data_ptr());
  }
  finish(state, c.x.size(0));
}

void hash_fwd(benchmark::State& state, const HashGridConfig& cfg, int64_t spr) {
  set_threads(state);
  GridCase c = make_case(cfg, spr);
  torch::NoGradGuard no_grad;
  for (auto _ : state) {
    torch::Tensor out = hash_grid_encode(c.x, c.table, c.layout);
    benchmark::DoNotOptimize(out.data_ptr());
  }
  finish(state, c.x.size(0));
}

// The raw backward kernel (it zeroes the gradient buffer itself, level by level).
void hash_bwd(benchmark::State& state, const HashGridConfig& cfg, int64_t spr) {
  set_threads(state);
  GridCase c = make_case(cfg, spr);
  torch::Tensor grad = torch::empty_like(c.table);
  const int nt = torch::get_num_threads();
  for (auto _ : state) {
    hash_grid_backward_cpu<float>(c.x.data_ptr<float>(), c.x.size(0), nullptr,
                                  c.upstream.data_ptr<float>(), c.layout, grad.data_ptr<float>(),
                                  nullptr, nt);
    benchmark::DoNotOptimize(grad.data_ptr());
  }
  finish(state, c.x.size(0));
}

void hash_reference_fwd_bwd(benchmark::State& state, const HashGridConfig& cfg, int64_t spr) {
  set_threads(state);
  GridCase c = make_case(cfg, spr);
  torch::Tensor table = c.table.clone().set_requires_grad(true);
  for (auto _ : state) {
    table.mutable_grad().reset();
    torch::Tensor out = hash_grid_encode_reference(c.x, table, c.layout);
    out.backward(c.upstream);
    benchmark::DoNotOptimize(table.grad().data_ptr());
  }
  finish(state, c.x.size(0));
}

#define NERAF_THREADS ->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()

BENCHMARK_CAPTURE(hash_fwd_bwd, main_196k, main_grid(), 48, false)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(hash_fwd_bwd, main_196k_with_grad_x, main_grid(), 48, true) NERAF_THREADS;
BENCHMARK_CAPTURE(hash_fwd, main_196k, main_grid(), 48)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(hash_bwd, main_196k, main_grid(), 48)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(hash_reference_fwd_bwd, main_196k, main_grid(), 48)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(3);

BENCHMARK_CAPTURE(hash_fwd_bwd, prop1_1048k, proposal_grid(128), 256, false) NERAF_THREADS;
BENCHMARK_CAPTURE(hash_fwd, prop1_1048k, proposal_grid(128), 256) NERAF_THREADS;
BENCHMARK_CAPTURE(hash_bwd, prop1_1048k, proposal_grid(128), 256) NERAF_THREADS;
BENCHMARK_CAPTURE(hash_fwd_bwd, prop2_393k, proposal_grid(256), 96, false) NERAF_THREADS;
BENCHMARK_CAPTURE(hash_fwd, prop2_393k, proposal_grid(256), 96) NERAF_THREADS;
BENCHMARK_CAPTURE(hash_bwd, prop2_393k, proposal_grid(256), 96) NERAF_THREADS;

// ---- SH encoding -----------------------------------------------------------------------------

torch::Tensor random_dirs(int64_t n) {
  torch::manual_seed(3);
  const torch::Tensor d = torch::randn({n, 3});
  return (d / d.norm(2, 1, true)).contiguous();
}

void sh_fwd(benchmark::State& state) {
  set_threads(state);
  const torch::Tensor dirs = random_dirs(kRays * 48);
  torch::NoGradGuard no_grad;
  for (auto _ : state) benchmark::DoNotOptimize(sh_encode(dirs).data_ptr());
  finish(state, dirs.size(0));
}

void sh_fwd_bwd(benchmark::State& state, bool reference) {
  set_threads(state);
  torch::Tensor dirs = random_dirs(kRays * 48).set_requires_grad(true);
  const torch::Tensor up = torch::randn({dirs.size(0), 16});
  for (auto _ : state) {
    dirs.mutable_grad().reset();
    torch::Tensor y = reference ? sh_encode_reference(dirs) : sh_encode(dirs);
    y.backward(up);
    benchmark::DoNotOptimize(dirs.grad().data_ptr());
  }
  finish(state, dirs.size(0));
}

BENCHMARK(sh_fwd) NERAF_THREADS;
BENCHMARK_CAPTURE(sh_fwd_bwd, op_196k, false) NERAF_THREADS;
BENCHMARK_CAPTURE(sh_fwd_bwd, reference_196k, true) NERAF_THREADS;

}  // namespace
}  // namespace neraf::nerf

int main(int argc, char** argv) { return neraf::bench::run_benchmarks(argc, argv); }
