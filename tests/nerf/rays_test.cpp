#include "neraf/nerf/rays.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

using namespace neraf::nerf;

TEST(Rays, KnownPixelIdentityPose) {
  neraf::data::Intrinsics k;
  k.fx = 100;
  k.fy = 80;
  k.cx = 50;
  k.cy = 40;
  k.width = 100;
  k.height = 80;
  const auto c2w = torch::cat({torch::eye(3), torch::tensor({{1.0f}, {2.0f}, {3.0f}})}, 1);
  const RayBundle rays = camera_rays(c2w, k);
  ASSERT_EQ(rays.size(), 100 * 80);
  // Row 30, column 60 → pixel centre (60.5, 30.5): x = 0.105, y_cv = −0.11875 → OpenGL (0.105,
  // +0.11875, −1), normalised.
  const int64_t i = 30 * 100 + 60;
  auto d = torch::tensor({0.105f, 0.11875f, -1.0f});
  d = d / d.norm();
  EXPECT_TRUE(torch::allclose(rays.directions[i], d, 1e-6, 1e-6));
  EXPECT_TRUE(torch::allclose(rays.origins[i], torch::tensor({1.0f, 2.0f, 3.0f})));
  // The principal point looks straight down −z.
  const RayBundle centre = rays_from_pixels(c2w.unsqueeze(0), intrinsics_row(k).unsqueeze(0),
                                            torch::tensor({50.0f}), torch::tensor({40.0f}));
  EXPECT_TRUE(torch::allclose(centre.directions[0], torch::tensor({0.0f, 0.0f, -1.0f})));
}

TEST(Rays, PoseRotationIsApplied) {
  neraf::data::Intrinsics k{10, 10, 5, 5, 10, 10};
  // Camera rotated 90° about +y: its −z (forward) axis points to world −x.
  const auto rot = torch::tensor({{0.0f, 0.0f, 1.0f}, {0.0f, 1.0f, 0.0f}, {-1.0f, 0.0f, 0.0f}});
  const auto c2w = torch::cat({rot, torch::zeros({3, 1})}, 1);
  const RayBundle r = rays_from_pixels(c2w.unsqueeze(0), intrinsics_row(k).unsqueeze(0),
                                       torch::tensor({5.0f}), torch::tensor({5.0f}));
  EXPECT_TRUE(torch::allclose(r.directions[0], torch::tensor({-1.0f, 0.0f, 0.0f}), 1e-6, 1e-6));
}

TEST(Rays, UndistortInvertsDistort) {
  const auto x = torch::tensor({{0.1, -0.2}, {0.3, 0.25}, {-0.4, 0.05}, {0.0, 0.0}},
                               torch::kFloat64);
  const auto dist =
      torch::tensor({-0.1, 0.02, 0.005, 0.001, -0.002}, torch::kFloat64).repeat({4, 1});
  const auto xd = distort_opencv(x, dist);
  EXPECT_FALSE(torch::allclose(xd, x));
  EXPECT_TRUE(torch::allclose(undistort_opencv(xd, dist), x, 1e-9, 1e-9));
}

TEST(Rays, DistortedCameraRayPassesThroughTheUndistortedPoint) {
  neraf::data::Intrinsics k{100, 100, 50, 50, 100, 100, -0.2, 0.05, 0.001, 0.002, 0.01};
  // The pixel where the distorted image shows the point with normalised coordinates (0.3, −0.1).
  const auto p = torch::tensor({{0.3, -0.1}}, torch::kFloat64);
  const auto pd = distort_opencv(p, torch::tensor({{-0.2, 0.05, 0.01, 0.001, 0.002}}, torch::kFloat64));
  const float px = static_cast<float>(pd[0][0].item<double>() * 100 + 50);
  const float py = static_cast<float>(pd[0][1].item<double>() * 100 + 50);
  const auto c2w = torch::cat({torch::eye(3), torch::zeros({3, 1})}, 1).unsqueeze(0);
  const RayBundle r = rays_from_pixels(c2w, intrinsics_row(k).unsqueeze(0), torch::tensor({px}),
                                       torch::tensor({py}));
  auto want = torch::tensor({0.3f, 0.1f, -1.0f});
  want = want / want.norm();
  EXPECT_TRUE(torch::allclose(r.directions[0], want, 1e-5, 1e-5));
}
