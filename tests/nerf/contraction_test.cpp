#include "neraf/nerf/contraction.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <limits>

using namespace neraf::nerf;

TEST(Contraction, InsideUnitCubeIsIdentity) {
  const auto x = torch::tensor({{0.5, -0.25, 0.9}, {0.0, 0.0, 0.0}, {1.0, -1.0, 0.3}});
  EXPECT_TRUE(torch::allclose(scene_contract(x), x));
}

TEST(Contraction, OutsideValuesMatchTheLInfFormula) {
  const auto x = torch::tensor({{2.0, 0.0, 0.0}, {2.0, 1.0, 0.0}, {-4.0, 1.0, 2.0}});
  // (2 − 1/m)·x/m with m = ‖x‖∞: m=2 → 0.75 x; m=4 → 0.4375 x.
  const auto want = torch::tensor({{1.5, 0.0, 0.0}, {1.5, 0.75, 0.0}, {-1.75, 0.4375, 0.875}});
  EXPECT_TRUE(torch::allclose(scene_contract(x), want, 1e-6, 1e-6));
  // Far away points approach the cube's surface ±2 but never reach it.
  const auto far = scene_contract(torch::tensor({{1e6f, 3.0f, -2.0f}}));
  EXPECT_LT(far[0][0].item<float>(), 2.0f);
  EXPECT_GT(far[0][0].item<float>(), 1.9999f);
}

TEST(Contraction, GridInputAndSelector) {
  const float inf = std::numeric_limits<float>::infinity();
  const auto x = torch::tensor({{0.0f, 0.0f, 0.0f}, {2.0f, 1.0f, 0.0f}, {inf, 0.0f, 0.0f}});
  const GridInput g = contract_to_grid_input(x);
  EXPECT_TRUE(torch::allclose(g.u[0], torch::tensor({0.5f, 0.5f, 0.5f})));
  EXPECT_TRUE(torch::allclose(g.u[1], torch::tensor({3.5f / 4, 2.75f / 4, 0.5f})));
  EXPECT_TRUE(g.selector[0].item<bool>());
  EXPECT_TRUE(g.selector[1].item<bool>());
  // ∞ contracts to NaN; it is deselected and its grid input zeroed (density 0 downstream).
  EXPECT_FALSE(g.selector[2].item<bool>());
  EXPECT_TRUE(torch::equal(g.u[2], torch::zeros({3})));
  // u given directly: the boundary of the cube is outside (strict inequalities, as nerfstudio).
  const GridInput b = grid_input_from_u(torch::tensor({{0.0f, 0.5f, 0.5f}, {0.2f, 0.5f, 0.99f}}));
  EXPECT_FALSE(b.selector[0].item<bool>());
  EXPECT_TRUE(b.selector[1].item<bool>());
}

TEST(Contraction, GradientMatchesFiniteDifferences) {
  auto x = torch::tensor({{0.3, -0.2, 0.1}, {2.0, 1.0, -0.5}, {-3.0, 0.5, 2.5}},
                         torch::kFloat64)
               .requires_grad_(true);
  const auto w = torch::tensor({{0.7, -1.1, 0.4}, {0.2, 0.9, -0.3}, {1.5, 0.1, -0.8}},
                               torch::kFloat64);
  (scene_contract(x) * w).sum().backward();
  const auto g = x.grad().clone();
  EXPECT_TRUE(torch::isfinite(g).all().item<bool>());
  const double h = 1e-6;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      auto xp = x.detach().clone(), xm = x.detach().clone();
      xp[i][j] += h;
      xm[i][j] -= h;
      const double fd =
          ((scene_contract(xp) * w).sum() - (scene_contract(xm) * w).sum()).item<double>() / (2 * h);
      EXPECT_NEAR(g[i][j].item<double>(), fd, 1e-6) << i << "," << j;
    }
}
