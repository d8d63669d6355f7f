#include "neraf/nerf/camera_optimizer.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

using namespace neraf::nerf;

TEST(CameraOptimizer, ZeroTangentIsTheIdentity) {
  const auto m = exp_map_so3xr3(torch::zeros({3, 6}));
  const auto id = torch::cat({torch::eye(3), torch::zeros({3, 1})}, 1);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(torch::equal(m[i], id));
}

TEST(CameraOptimizer, RotationAndTranslationOfAKnownTangent) {
  const double a = M_PI / 2;
  const auto m = exp_map_so3xr3(torch::tensor({{1.0, 2.0, 3.0, 0.0, 0.0, a}}, torch::kFloat64));
  const auto want = torch::tensor({{0.0, -1.0, 0.0, 1.0}, {1.0, 0.0, 0.0, 2.0}, {0.0, 0.0, 1.0, 3.0}},
                                  torch::kFloat64);
  EXPECT_TRUE(torch::allclose(m[0], want, 1e-12, 1e-12));
}

TEST(CameraOptimizer, AtZeroRaysAreUnchangedAndGradientsAreFinite) {
  CameraOptConfig cfg;  // SO3xR3
  CameraOptimizer opt(cfg, 4);
  RayBundle rays;
  rays.origins = torch::rand({5, 3});
  auto d = torch::rand({5, 3}) - 0.5;
  rays.directions = d / d.norm(2, 1, true);
  rays.camera_indices = torch::tensor({0, 1, 3, -1, 2}, torch::kInt64);
  const RayBundle out = opt->apply(rays);
  EXPECT_TRUE(torch::allclose(out.origins, rays.origins));
  EXPECT_TRUE(torch::allclose(out.directions, rays.directions, 1e-6, 1e-7));
  auto reg = opt->regularizer();
  EXPECT_EQ(reg.item<float>(), 0.0f);
  (reg + out.origins.sum() + out.directions.sum()).backward();
  ASSERT_TRUE(opt->pose_adjustment.grad().defined());
  EXPECT_TRUE(torch::isfinite(opt->pose_adjustment.grad()).all().item<bool>());
  // Translation gradient of Σ origins is the ray count per camera (camera 3 has one ray).
  EXPECT_FLOAT_EQ(opt->pose_adjustment.grad()[3][0].item<float>(), 1.0f);
}

TEST(CameraOptimizer, RegularizerIsTheWeightedMeanNorms) {
  CameraOptConfig cfg;
  CameraOptimizer opt(cfg, 2);
  {
    torch::NoGradGuard g;
    opt->pose_adjustment.copy_(torch::tensor({{3.0f, 4.0f, 0.0f, 0.0f, 0.0f, 2.0f},
                                              {0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f}}));
  }
  EXPECT_NEAR(opt->regularizer().item<float>(), 1e-2 * (5 + 1) / 2.0 + 1e-3 * (2 + 0) / 2.0, 1e-7);
}

TEST(CameraOptimizer, OffHasNoParametersAndChangesNothing) {
  CameraOptConfig cfg;
  cfg.mode = CameraOptMode::off;
  CameraOptimizer opt(cfg, 3);
  EXPECT_TRUE(opt->parameters().empty());
  RayBundle rays;
  rays.origins = torch::rand({2, 3});
  rays.directions = torch::rand({2, 3});
  rays.camera_indices = torch::zeros({2}, torch::kInt64);
  EXPECT_TRUE(torch::equal(opt->apply(rays).origins, rays.origins));
  EXPECT_EQ(opt->regularizer().item<float>(), 0.0f);
}
