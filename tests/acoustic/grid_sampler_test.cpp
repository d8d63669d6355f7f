#include "neraf/acoustic/grid_sampler.h"

#include <gtest/gtest.h>
#include <torch/torch.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace neraf::acoustic {
namespace {

using torch::indexing::Slice;

// Analytic toy field: density = 100·e^w·u_x, rgb = u + 0.1·d (+ w·u_y on green), so every output
// depends on the learnable scalar w.
struct ToyField {
  torch::Tensor w = torch::zeros({}, torch::requires_grad());
  int calls = 0;
  std::pair<torch::Tensor, torch::Tensor> operator()(const torch::Tensor& u,
                                                     const torch::Tensor& d) {
    ++calls;
    auto density = 100.0 * torch::exp(w) * u.select(1, 0);
    auto rgb = u + 0.1 * d;
    rgb = torch::stack({rgb.select(1, 0), rgb.select(1, 1) + w * u.select(1, 1), rgb.select(1, 2)},
                       1);
    return {density, rgb};
  }
};

FieldQueryFn as_fn(ToyField& f) {
  return [&f](const torch::Tensor& u, const torch::Tensor& d) { return f(u, d); };
}

TEST(GridSampler, CellCentresAndFlatOrder) {
  const auto c = grid_cell_centres_1d(128);
  ASSERT_EQ(c.size(0), 128);
  EXPECT_FLOAT_EQ(c[0].item<float>(), 1.0f / 256);
  EXPECT_FLOAT_EQ(c[1].item<float>(), 3.0f / 256);
  EXPECT_FLOAT_EQ(c[127].item<float>(), 255.0f / 256);
  // x-major, z fastest: flat n = (i·S + j)·S + k.
  const auto cells = grid_cell_centres(4, 0, 64);
  const int n = (2 * 4 + 1) * 4 + 3;  // (i, j, k) = (2, 1, 3)
  EXPECT_FLOAT_EQ(cells[n][0].item<float>(), 2.5f / 4);
  EXPECT_FLOAT_EQ(cells[n][1].item<float>(), 1.5f / 4);
  EXPECT_FLOAT_EQ(cells[n][2].item<float>(), 3.5f / 4);
  // Wrapping past S³.
  const auto wrap = grid_cell_centres(4, 62, 4);
  EXPECT_TRUE(torch::equal(wrap[2], cells[0]));
  EXPECT_TRUE(torch::equal(wrap[1], cells[63]));
}

TEST(GridSampler, InitialGridHoldsCoordinates) {
  GridSamplerOptions o;
  o.resolution = 4;
  GridSampler g(o);
  const auto& grid = g->grid();
  ASSERT_EQ(grid.sizes(), (std::vector<int64_t>{7, 4, 4, 4}));
  EXPECT_EQ(grid.slice(0, 0, 4).abs().sum().item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(grid[4][2][1][3].item<float>(), 2.5f / 4);
  EXPECT_FLOAT_EQ(grid[5][2][1][3].item<float>(), 1.5f / 4);
  EXPECT_FLOAT_EQ(grid[6][2][1][3].item<float>(), 3.5f / 4);
  EXPECT_EQ(g->pointer(), 0);
}

TEST(GridSampler, ReferenceDirectionsExact) {
  const auto d = reference_view_directions();
  ASSERT_EQ(d.sizes(), (std::vector<int64_t>{18, 3}));
  const double s = std::sqrt(3.0) / 2.0;  // sin(π/3) = sin(2π/3)
  // φ = π/3 (cos 0.5), φ = 0 (cos 1), φ = −π (cos −1); θ = 0, π/3, 2π/3, π, 4π/3, 5π/3.
  const double sin_theta[6] = {0, s, s, 0, -s, -s};
  const double cos_phi[3] = {0.5, 1.0, -1.0};
  for (int p = 0; p < 3; ++p) {
    for (int k = 0; k < 6; ++k) {
      const auto row = d[p * 6 + k];
      EXPECT_NEAR(row[0].item<float>(), cos_phi[p] * sin_theta[k], 1e-6);
      EXPECT_NEAR(row[1].item<float>(), cos_phi[p] * sin_theta[k], 1e-6);
      EXPECT_NEAR(row[2].item<float>(), sin_theta[k], 1e-6);
    }
  }
  // The documented degeneracy: 6 zero vectors, norms 1.061 / 1.5 otherwise.
  const auto norms = d.norm(2, 1);
  EXPECT_EQ((norms < 1e-6).sum().item<int64_t>(), 6);
  EXPECT_NEAR(d[1].norm().item<float>(), 1.0607, 1e-4);
  EXPECT_NEAR(d[7].norm().item<float>(), 1.5, 1e-6);
}

TEST(GridSampler, SpreadDirectionsAreWellSpreadUnitVectors) {
  const auto d = fibonacci_sphere_directions(18).to(torch::kFloat64);
  ASSERT_EQ(d.sizes(), (std::vector<int64_t>{18, 3}));
  EXPECT_LT((d.norm(2, 1) - 1.0).abs().max().item<double>(), 1e-6);
  const auto cosines = torch::mm(d, d.t()) - 2.0 * torch::eye(18, torch::kFloat64);
  const double min_angle_deg = std::acos(cosines.max().item<double>()) * 180.0 / M_PI;
  EXPECT_GT(min_angle_deg, 35.0);  // 18 points: the optimum is ≈ 50°, duplicates would give 0°
  EXPECT_LT(d.mean(0).norm().item<double>(), 0.1);
}

TEST(GridSampler, UpdateWritesChannelsAndAlpha) {
  GridSamplerOptions o;
  o.resolution = 4;
  o.cells_per_update = 64;
  GridSampler g(o);
  ToyField field;
  g->update(as_fn(field));
  const auto grid = g->grid().detach();
  const auto u = grid_cell_centres(4, 0, 64);             // [64, 3]
  const auto dmean = g->directions().mean(0);             // [3]
  const auto got = grid.slice(0, 0, 4).reshape({4, 64});  // [4, 64]
  for (int c = 0; c < 3; ++c) {
    EXPECT_TRUE(torch::allclose(got[c], u.select(1, c) + 0.1 * dmean[c], 1e-5, 1e-6)) << c;
  }
  const auto alpha = 1.0 - torch::exp(-0.01 * 100.0 * u.select(1, 0));
  EXPECT_TRUE(torch::allclose(got[3], alpha, 1e-5, 1e-6));
  // Coordinates untouched.
  EXPECT_TRUE(torch::allclose(grid.slice(0, 4, 7).reshape({3, 64}), u.t()));
  EXPECT_EQ(g->pointer(), 0);  // 64 of 64 cells: wrapped
}

TEST(GridSampler, AlphaIsClipped) {
  GridSamplerOptions o;
  o.resolution = 2;
  o.cells_per_update = 8;
  GridSampler g(o);
  auto neg = [](const torch::Tensor& u, const torch::Tensor&) {
    return std::make_pair(-1000.0 * torch::ones({u.size(0)}), torch::zeros({u.size(0), 3}));
  };
  g->update(neg);
  EXPECT_EQ(g->grid()[3].abs().max().item<float>(), 0.0f);  // 1 − e^{10} < 0 → clipped to 0
  auto huge = [](const torch::Tensor& u, const torch::Tensor&) {
    return std::make_pair(1e6 * torch::ones({u.size(0)}), torch::zeros({u.size(0), 3}));
  };
  g->update(huge);
  EXPECT_EQ(g->grid()[3].min().item<float>(), 1.0f);
}

TEST(GridSampler, RoundRobinPointerWraps) {
  GridSamplerOptions o;
  o.resolution = 4;  // 64 cells
  o.cells_per_update = 24;
  GridSampler g(o);
  int call = 0;
  // Density encodes the call number so we can tell which cells each update wrote.
  auto field = [&call](const torch::Tensor& u, const torch::Tensor&) {
    return std::make_pair(torch::full({u.size(0)}, 100.0 * call), torch::zeros({u.size(0), 3}));
  };
  auto alpha_of = [](int c) { return static_cast<float>(1.0 - std::exp(-0.01 * 100.0 * c)); };
  std::vector<int> writer(64, -1);
  const int expected_first[4] = {0, 24, 48, 8};
  for (call = 1; call <= 4; ++call) {
    const auto flat = g->update(field);
    ASSERT_EQ(flat.size(0), 24);
    EXPECT_EQ(flat[0].item<int64_t>(), expected_first[call - 1]);
    for (int i = 0; i < 24; ++i) writer[flat[i].item<int64_t>()] = call;
    EXPECT_EQ(g->pointer(), (24 * call) % 64);
    const auto a = g->grid()[3].reshape({64});
    for (int n = 0; n < 64; ++n) {
      const float want = writer[n] < 0 ? 0.0f : alpha_of(writer[n]);
      EXPECT_NEAR(a[n].item<float>(), want, 1e-6) << "call " << call << " cell " << n;
    }
  }
  // Call 3 wrote 48..63 and 0..7; call 4 wrote 8..31.
  EXPECT_EQ(writer[63], 3);
  EXPECT_EQ(writer[0], 3);
  EXPECT_EQ(writer[7], 3);
  EXPECT_EQ(writer[8], 4);
  EXPECT_EQ(writer[31], 4);
  EXPECT_EQ(writer[32], 2);
}

TEST(GridSampler, OnlyFreshCellsCarryGradient) {
  GridSamplerOptions o;
  o.resolution = 4;
  o.cells_per_update = 20;
  GridSampler g(o);
  ToyField field;
  g->update(as_fn(field));  // cells 0..19
  g->update(as_fn(field));  // cells 20..39: the only differentiable ones now
  const auto weights = torch::rand({7, 4, 4, 4});
  (g->grid() * weights).sum().backward({}, /*retain_graph=*/true);
  ASSERT_TRUE(field.w.grad().defined());
  const double got = field.w.grad().item<double>();
  EXPECT_NE(got, 0.0);

  // Reference: the same loss restricted to the fresh cells, recomputed from the field directly.
  ToyField ref;
  const auto u = grid_cell_centres(4, 20, 20);  // [20, 3]
  const auto values = g->query_cells(
      [&ref](const torch::Tensor& a, const torch::Tensor& b) { return ref(a, b); }, u);  // [4, 20]
  const auto w_fresh = weights.slice(0, 0, 4).reshape({4, 64}).slice(1, 20, 40);
  (values * w_fresh).sum().backward();
  EXPECT_NEAR(got, ref.w.grad().item<double>(), 1e-6 * std::abs(got) + 1e-9);

  // A loss on the older cells only has no path to the field.
  field.w.mutable_grad().zero_();
  g->grid().slice(0, 0, 4).reshape({4, 64}).slice(1, 0, 20).sum().backward();
  EXPECT_EQ(field.w.grad().item<double>(), 0.0);
}

TEST(GridSampler, EvalModeDoesNotUpdate) {
  GridSamplerOptions o;
  o.resolution = 4;
  o.cells_per_update = 8;
  GridSampler g(o);
  ToyField field;
  g->eval();
  const auto before = g->grid().clone();
  EXPECT_EQ(g->update(as_fn(field)).numel(), 0);
  EXPECT_EQ(field.calls, 0);
  EXPECT_TRUE(torch::equal(before, g->grid()));
  EXPECT_EQ(g->pointer(), 0);
}

TEST(GridSampler, RefreshAllFillsEveryCellWithoutGrad) {
  GridSamplerOptions o;
  o.resolution = 4;
  GridSampler g(o);
  ToyField field;
  g->refresh_all(as_fn(field), 10);
  EXPECT_EQ(field.calls, 7);
  EXPECT_FALSE(g->grid().requires_grad());
  const auto u = grid_cell_centres(4, 0, 64);
  EXPECT_TRUE(torch::allclose(g->grid()[3].reshape({64}), 1.0 - torch::exp(-1.0 * u.select(1, 0)),
                              1e-5, 1e-6));
  EXPECT_EQ(g->pointer(), 0);
}

TEST(GridSampler, ReferenceModeUsesEighteenReferenceVectors) {
  GridSamplerOptions o;
  o.resolution = 2;
  o.cells_per_update = 8;
  o.view_directions = ViewDirections::kReference;
  GridSampler g(o);
  EXPECT_TRUE(torch::equal(g->directions(), reference_view_directions()));
  int64_t seen = 0;
  g->update([&seen](const torch::Tensor& u, const torch::Tensor& d) {
    seen = d.size(0);
    return std::make_pair(torch::zeros({u.size(0)}), torch::zeros({u.size(0), 3}));
  });
  EXPECT_EQ(seen, 8 * 18);
  EXPECT_EQ(parse_view_directions("spread"), ViewDirections::kSpread);
  EXPECT_EQ(parse_view_directions("reference"), ViewDirections::kReference);
  EXPECT_THROW(parse_view_directions("random"), std::exception);
}

TEST(GridSampler, StateRoundTripsThroughCheckpoint) {
  GridSamplerOptions o;
  o.resolution = 4;
  o.cells_per_update = 24;
  GridSampler g(o);
  ToyField field;
  g->update(as_fn(field));
  const auto path = (std::filesystem::temp_directory_path() /
                     ("neraf_grid_" + std::to_string(::getpid()) + ".pt"))
                        .string();
  torch::save(g, path);
  GridSampler h(o);
  torch::load(h, path);
  std::filesystem::remove(path);
  EXPECT_TRUE(torch::equal(h->grid(), g->grid().detach()));
  EXPECT_EQ(h->pointer(), 24);
}

}  // namespace
}  // namespace neraf::acoustic
