#include "neraf/nerf/volume_rendering.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

using namespace neraf::nerf;

// One ray, three samples, by hand: σ = (1, 2, 3), δ = (0.5, 0.25, 1) → σδ = (0.5, 0.5, 3).
TEST(VolumeRendering, ThreeSampleWeightsByHand) {
  const auto dens = torch::tensor({{1.0, 2.0, 3.0}}, torch::kFloat64);
  const auto deltas = torch::tensor({{0.5, 0.25, 1.0}}, torch::kFloat64);
  const auto w = compute_weights(dens, deltas);
  const double a0 = 1 - std::exp(-0.5), a1 = 1 - std::exp(-0.5), a2 = 1 - std::exp(-3.0);
  const double w0 = a0, w1 = a1 * std::exp(-0.5), w2 = a2 * std::exp(-1.0);
  EXPECT_NEAR(w[0][0].item<double>(), w0, 1e-12);
  EXPECT_NEAR(w[0][1].item<double>(), w1, 1e-12);
  EXPECT_NEAR(w[0][2].item<double>(), w2, 1e-12);
  EXPECT_NEAR(accumulation(w)[0].item<double>(), w0 + w1 + w2, 1e-12);

  // Colours red, green, blue; background = last sample (blue) fills 1 − Σw.
  const auto rgb = torch::tensor({{{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}},
                                 torch::kFloat64);
  const auto c = composite_rgb(w, rgb);
  const double acc = w0 + w1 + w2;
  EXPECT_NEAR(c[0][0].item<double>(), w0, 1e-12);
  EXPECT_NEAR(c[0][1].item<double>(), w1, 1e-12);
  EXPECT_NEAR(c[0][2].item<double>(), w2 + (1 - acc), 1e-12);

  // Bins edges t = (1, 1.5, 1.75, 2.75) → midpoints (1.25, 1.625, 2.25).
  const auto tdist = torch::tensor({{1.0, 1.5, 1.75, 2.75}}, torch::kFloat64);
  const double exp_d = (w0 * 1.25 + w1 * 1.625 + w2 * 2.25) / acc;
  EXPECT_NEAR(expected_depth(w, tdist)[0].item<double>(), exp_d, 1e-9);
  // Cumulative weights 0.393, 0.632, 0.95: the first ≥ 0.5 is the second sample.
  EXPECT_NEAR(median_depth(w, tdist)[0].item<double>(), 1.625, 1e-12);
}

TEST(VolumeRendering, EmptyRayShowsBackgroundAndMedianFallsToLastSample) {
  const auto w = compute_weights(torch::zeros({1, 4}), torch::ones({1, 4}));
  EXPECT_TRUE(torch::equal(w, torch::zeros({1, 4})));
  const auto rgb = torch::rand({1, 4, 3});
  EXPECT_TRUE(torch::allclose(composite_rgb(w, rgb), rgb[0][3].unsqueeze(0)));
  const auto tdist = torch::tensor({{0.f, 1.f, 2.f, 3.f, 4.f}});
  EXPECT_FLOAT_EQ(median_depth(w, tdist)[0].item<float>(), 3.5f);
}

TEST(VolumeRendering, InfiniteDensityGivesNoNaN) {
  const auto dens = torch::tensor({{0.0f, std::numeric_limits<float>::infinity(), 1.0f}});
  const auto w = compute_weights(dens, torch::ones({1, 3}));
  EXPECT_TRUE(torch::isfinite(w).all().item<bool>());
  EXPECT_NEAR(w[0][1].item<float>(), 1.0f, 1e-6);
}

TEST(VolumeRendering, WeightsGradientMatchesFiniteDifferences) {
  auto dens = torch::tensor({{0.3, 1.2, 0.7, 2.0}}, torch::kFloat64).requires_grad_(true);
  const auto deltas = torch::tensor({{0.2, 0.4, 0.1, 0.5}}, torch::kFloat64);
  const auto coef = torch::tensor({{1.0, -2.0, 0.5, 3.0}}, torch::kFloat64);
  (compute_weights(dens, deltas) * coef).sum().backward();
  for (int i = 0; i < 4; ++i) {
    auto p = dens.detach().clone(), m = dens.detach().clone();
    p[0][i] += 1e-6;
    m[0][i] -= 1e-6;
    const double fd = ((compute_weights(p, deltas) * coef).sum() -
                       (compute_weights(m, deltas) * coef).sum())
                          .item<double>() /
                      2e-6;
    EXPECT_NEAR(dens.grad()[0][i].item<double>(), fd, 1e-7);
  }
}
