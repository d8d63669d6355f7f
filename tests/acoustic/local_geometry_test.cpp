// Geometry per query (acoustic/local_geometry.h) against slow references: trilinear sampling
// written out voxel by voxel (values, and gradients through a gather-based reference), the world
// map and contraction by hand, and the feature layout [mic, source, mean, max].
#include "neraf/acoustic/local_geometry.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>

namespace neraf::acoustic {
namespace {

// One axis of align_corners = false sampling with border clamping: the two voxels and the weight
// of the upper one, for u ∈ [0, 1] over n voxels centred at (i + 0.5)/n.
struct Axis {
  int64_t lo, hi;
  double w_hi;
};
Axis axis(double u, int64_t n) {
  const double c = std::clamp(u * static_cast<double>(n) - 0.5, 0.0, static_cast<double>(n - 1));
  const auto lo = static_cast<int64_t>(std::floor(c));
  return {lo, std::min(lo + 1, n - 1), c - static_cast<double>(lo)};
}

// volume [L, D, H, W] (float64), u [N, 3] → [N, L], as a differentiable sum of gathered voxels.
torch::Tensor reference_sample(const torch::Tensor& volume, const torch::Tensor& u) {
  const int64_t n = u.size(0);
  std::vector<torch::Tensor> rows;
  for (int64_t i = 0; i < n; ++i) {
    const Axis x = axis(u[i][0].item<double>(), volume.size(1));
    const Axis y = axis(u[i][1].item<double>(), volume.size(2));
    const Axis z = axis(u[i][2].item<double>(), volume.size(3));
    torch::Tensor acc = torch::zeros({volume.size(0)}, torch::kFloat64);
    for (int dx = 0; dx < 2; ++dx)
      for (int dy = 0; dy < 2; ++dy)
        for (int dz = 0; dz < 2; ++dz) {
          const double w =
              (dx ? x.w_hi : 1 - x.w_hi) * (dy ? y.w_hi : 1 - y.w_hi) * (dz ? z.w_hi : 1 - z.w_hi);
          acc = acc + w * volume.select(1, dx ? x.hi : x.lo)
                              .select(1, dy ? y.hi : y.lo)
                              .select(1, dz ? z.hi : z.lo);
        }
    rows.push_back(acc);
  }
  return torch::stack(rows);
}

TEST(LocalGeometry, SampleVolumeMatchesTrilinearReferenceInValuesAndGradients) {
  torch::manual_seed(3);
  // Unequal sides, so an axis swap would be caught; points inside, on voxel centres and past the
  // border (clamped).
  const torch::Tensor volume = torch::randn({5, 4, 6, 7}, torch::kFloat64).requires_grad_();
  torch::Tensor u = torch::rand({40, 3}, torch::kFloat64);
  u[0] = torch::tensor({0.125, 0.25, 0.5}, torch::kFloat64);  // (x, y, z) ↦ fractional voxels
  u[1] = torch::tensor({0.0, 1.0, 0.01}, torch::kFloat64);
  u[2] = torch::tensor({-0.2, 1.3, 0.999}, torch::kFloat64);
  const torch::Tensor got = sample_volume(volume, u);
  const torch::Tensor want = reference_sample(volume, u);
  ASSERT_EQ(got.sizes(), (std::vector<int64_t>{40, 5}));
  EXPECT_TRUE(torch::allclose(got, want, 1e-12, 1e-12)) << (got - want).abs().max();
  // A voxel centre returns that voxel: u = ((i + 0.5)/D, (j + 0.5)/H, (k + 0.5)/W).
  const torch::Tensor centre = torch::tensor({{1.5 / 4, 4.5 / 6, 2.5 / 7}}, torch::kFloat64);
  EXPECT_TRUE(torch::allclose(sample_volume(volume, centre)[0],
                              volume.select(1, 1).select(1, 4).select(1, 2), 1e-12, 1e-12));
  const torch::Tensor weights = torch::randn({40, 5}, torch::kFloat64);
  const torch::Tensor g_got = torch::autograd::grad({(got * weights).sum()}, {volume})[0];
  const torch::Tensor g_want = torch::autograd::grad({(want * weights).sum()}, {volume})[0];
  EXPECT_TRUE(torch::allclose(g_got, g_want, 1e-12, 1e-12)) << (g_got - g_want).abs().max();
}

TEST(LocalGeometry, WorldToGridInputAppliesTheMapThenTheContraction) {
  // p' = 0.5·(Rz90 p) + (0.1, 0, 0): Rz90 (x, y, z) = (−y, x, z).
  const WorldToField w = {0, -0.5, 0, 0.1, 0.5, 0, 0, 0, 0, 0, 0.5, 0};
  const torch::Tensor p = torch::tensor({{1.0, 0.4, -1.0}, {0.0, -6.0, 0.5}}, torch::kFloat64);
  const torch::Tensor u = world_to_grid_input(p, w);
  // First: p' = (−0.2 + 0.1, 0.5, −0.5), inside the unit cube: u = (p' + 2)/4.
  EXPECT_NEAR(u[0][0].item<double>(), (-0.1 + 2) / 4, 1e-6);
  EXPECT_NEAR(u[0][1].item<double>(), (0.5 + 2) / 4, 1e-6);
  EXPECT_NEAR(u[0][2].item<double>(), (-0.5 + 2) / 4, 1e-6);
  // Second: p' = (3.1, 0, 0.25), ‖p'‖∞ = 3.1: contract = (2 − 1/3.1)·p'/3.1.
  const double k = (2 - 1 / 3.1) / 3.1;
  EXPECT_NEAR(u[1][0].item<double>(), (k * 3.1 + 2) / 4, 1e-6);
  EXPECT_NEAR(u[1][1].item<double>(), 0.5, 1e-6);
  EXPECT_NEAR(u[1][2].item<double>(), (k * 0.25 + 2) / 4, 1e-6);
  // The identity map is the contraction alone.
  const torch::Tensor q = torch::tensor({{0.2, -0.4, 0.6}}, torch::kFloat64);
  EXPECT_TRUE(torch::allclose(world_to_grid_input(q, kIdentityWorldToField),
                              ((q + 2) / 4).to(torch::kFloat32)));
}

// A stride-2 convolution that copies its centre tap (kernel 5, padding 2, as ResNet3D's stem):
// map voxel o holds grid cell 2o, so reading the map at strided_map_coordinates(u) gives the grid
// at u wherever u is the centre of an even cell, for even and odd S.
TEST(LocalGeometry, StridedMapCoordinatesFindTheCellAVoxelIsCentredOn) {
  torch::manual_seed(8);
  for (int64_t s : {8, 9}) {
    const torch::Tensor grid = torch::randn({1, 1, s, s, s}, torch::kFloat64);
    torch::Tensor centre_tap = torch::zeros({1, 1, 5, 5, 5}, torch::kFloat64);
    centre_tap[0][0][2][2][2] = 1.0;
    const torch::Tensor map =
        torch::conv3d(grid, centre_tap, {}, /*stride=*/2, /*padding=*/2)[0];  // [1, S', S', S']
    ASSERT_EQ(map.size(1), (s + 1) / 2);
    std::vector<double> even_cells;
    for (int64_t i = 0; i < s; i += 2) even_cells.push_back((static_cast<double>(i) + 0.5) / s);
    for (double x : even_cells)
      for (double z : even_cells) {
        const torch::Tensor u = torch::tensor({{x, even_cells[1], z}}, torch::kFloat64);
        const double want = sample_volume(grid[0], u)[0][0].item<double>();
        const double got =
            sample_volume(map, strided_map_coordinates(u, s, map.size(1)))[0][0].item<double>();
        EXPECT_NEAR(got, want, 1e-12) << "S " << s << " at " << x << ", " << z;
      }
  }
  EXPECT_THROW(strided_map_coordinates(torch::zeros({1, 3}), 32, 15), c10::Error);
}

TEST(LocalGeometry, FeaturesAreMicSourceAndTheSegmentsMeanAndMax) {
  torch::manual_seed(5);
  const torch::Tensor volume = torch::rand({3, 8, 8, 8});
  const torch::Tensor mic = torch::rand({6, 3}), src = torch::rand({6, 3});
  const int64_t k = 5;
  const torch::Tensor f = local_geometry_features(volume, mic, src, k);
  ASSERT_EQ(f.sizes(), (std::vector<int64_t>{6, 12}));
  for (int64_t b = 0; b < 6; ++b) {
    std::vector<torch::Tensor> along;
    for (int64_t i = 0; i < k; ++i) {
      const double t = (static_cast<double>(i) + 0.5) / static_cast<double>(k);
      along.push_back(
          reference_sample(volume.to(torch::kFloat64),
                           (mic[b] + t * (src[b] - mic[b])).view({1, 3}).to(torch::kFloat64))[0]);
    }
    const torch::Tensor seg = torch::stack(along);  // [K, L]
    const torch::Tensor want = torch::cat(
        {reference_sample(volume.to(torch::kFloat64), mic[b].view({1, 3}).to(torch::kFloat64))[0],
         reference_sample(volume.to(torch::kFloat64), src[b].view({1, 3}).to(torch::kFloat64))[0],
         seg.mean(0), std::get<0>(seg.max(0))});
    EXPECT_TRUE(torch::allclose(f[b].to(torch::kFloat64), want, 1e-5, 1e-6)) << b;
  }
}

TEST(LocalGeometry, AWallBetweenMicAndSourceShowsInTheSegmentMaximumOnly) {
  // One channel, a slab at x ∈ voxels 7-8 of 16: a mic and a source on either side see it in
  // the segment's max; the same pair moved to one side does not.
  torch::Tensor volume = torch::zeros({1, 16, 16, 16});
  volume.select(1, 7).fill_(1.0);
  volume.select(1, 8).fill_(1.0);
  const torch::Tensor mic = torch::tensor({{0.2f, 0.5f, 0.5f}, {0.1f, 0.5f, 0.5f}});
  const torch::Tensor src = torch::tensor({{0.8f, 0.5f, 0.5f}, {0.3f, 0.5f, 0.5f}});
  const torch::Tensor f = local_geometry_features(volume, mic, src, 8);  // [2, 4]
  EXPECT_FLOAT_EQ(f[0][0].item<float>(), 0.0f);                          // at the mic
  EXPECT_FLOAT_EQ(f[0][1].item<float>(), 0.0f);                          // at the source
  EXPECT_GT(f[0][3].item<float>(), 0.5f);        // the wall, on the direct path
  EXPECT_FLOAT_EQ(f[1][3].item<float>(), 0.0f);  // no wall in between
}

TEST(LocalGeometry, BadShapesAreRefused) {
  const torch::Tensor volume = torch::zeros({2, 4, 4, 4});
  EXPECT_THROW(sample_volume(volume.view({2, 4, 16}), torch::zeros({1, 3})), c10::Error);
  EXPECT_THROW(sample_volume(volume, torch::zeros({1, 2})), c10::Error);
  EXPECT_THROW(local_geometry_features(volume, torch::zeros({2, 3}), torch::zeros({3, 3}), 4),
               c10::Error);
  EXPECT_THROW(local_geometry_features(volume, torch::zeros({2, 3}), torch::zeros({2, 3}), 0),
               c10::Error);
}

}  // namespace
}  // namespace neraf::acoustic
