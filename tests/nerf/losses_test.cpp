#include "neraf/nerf/losses.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

using namespace neraf::nerf;

namespace {

// Sorted random edges on [0, 1] with fixed ends: [R, S + 1].
torch::Tensor random_edges(int64_t R, int64_t S, torch::Generator& gen) {
  auto inner = std::get<0>(torch::sort(torch::rand({R, S - 1}, gen, torch::kFloat64), 1));
  return torch::cat({torch::zeros({R, 1}, torch::kFloat64), inner,
                     torch::ones({R, 1}, torch::kFloat64)},
                    1);
}

// Definition of the outer bound: Σ of envelope weights over the envelope intervals that overlap
// the target interval (touching from above counts, as the searchsorted form does).
torch::Tensor slow_outer(const torch::Tensor& t0, const torch::Tensor& t1, const torch::Tensor& y1) {
  auto out = torch::zeros({t0.size(0), t0.size(1) - 1}, torch::kFloat64);
  for (int64_t r = 0; r < t0.size(0); ++r)
    for (int64_t i = 0; i + 1 < t0.size(1); ++i) {
      double s = 0;
      for (int64_t j = 0; j + 1 < t1.size(1); ++j) {
        const bool overlap = t1[r][j + 1].item<double>() > t0[r][i].item<double>() &&
                             t1[r][j].item<double>() <= t0[r][i + 1].item<double>();
        if (overlap) s += y1[r][j].item<double>();
      }
      out[r][i] = s;
    }
  return out;
}

torch::Tensor slow_distortion(const torch::Tensor& w, const torch::Tensor& s) {
  torch::Tensor total = torch::zeros({}, torch::kFloat64);
  for (int64_t r = 0; r < w.size(0); ++r) {
    for (int64_t i = 0; i < w.size(1); ++i) {
      const auto mi = (s[r][i] + s[r][i + 1]) / 2;
      for (int64_t j = 0; j < w.size(1); ++j) {
        const auto mj = (s[r][j] + s[r][j + 1]) / 2;
        total = total + w[r][i] * w[r][j] * (mi - mj).abs();
      }
      total = total + w[r][i] * w[r][i] * (s[r][i + 1] - s[r][i]) / 3;
    }
  }
  return total / w.size(0);
}

}  // namespace

TEST(Losses, MseIsTheMeanSquaredError) {
  const auto a = torch::tensor({{0.0, 1.0}, {0.5, 0.5}});
  const auto b = torch::tensor({{1.0, 1.0}, {0.0, 0.5}});
  EXPECT_NEAR(mean_squared_error(a, b).item<double>(), (1.0 + 0.25) / 4, 1e-7);
}

TEST(Losses, OuterMatchesTheOverlapDefinition) {
  torch::Generator gen = at::detail::createCPUGenerator(11);
  const auto t0 = random_edges(5, 7, gen), t1 = random_edges(5, 9, gen);
  const auto y1 = torch::rand({5, 9}, gen, torch::kFloat64);
  EXPECT_TRUE(torch::allclose(outer_weights(t0, t1, y1), slow_outer(t0, t1, y1), 1e-12, 1e-12));
  // Identical bins: the outer weights are the weights themselves plus the touching neighbour
  // above (the right-closed convention).
  const auto same = outer_weights(t1, t1, y1);
  EXPECT_TRUE(torch::allclose(same, slow_outer(t1, t1, y1)));
}

TEST(Losses, InterlevelMatchesTheReferenceFormulaAndGradient) {
  torch::Generator gen = at::detail::createCPUGenerator(5);
  const int64_t R = 4;
  auto s_prop = random_edges(R, 12, gen), s_nerf = random_edges(R, 6, gen);
  auto w_prop = (torch::rand({R, 12}, gen, torch::kFloat64) * 0.2).requires_grad_(true);
  auto w_nerf = (torch::rand({R, 6}, gen, torch::kFloat64) * 0.3).requires_grad_(true);
  const auto loss = interlevel_loss({w_prop, w_nerf}, {s_prop, s_nerf});
  // Reference: mean(clip(w − outer, 0)² / (w + 1e-7)).
  const auto wo = slow_outer(s_nerf, s_prop, w_prop.detach());
  const auto ref = (torch::clamp_min(w_nerf.detach() - wo, 0).pow(2) / (w_nerf.detach() + 1e-7)).mean();
  EXPECT_NEAR(loss.item<double>(), ref.item<double>(), 1e-12);
  loss.backward();
  // Targets (the nerf level) are detached; the proposal weights get the gradient.
  EXPECT_FALSE(w_nerf.grad().defined() && w_nerf.grad().abs().sum().item<double>() > 0);
  ASSERT_TRUE(w_prop.grad().defined());
  for (int k = 0; k < 6; ++k) {
    auto p = w_prop.detach().clone(), m = w_prop.detach().clone();
    p[k % R][k] += 1e-7;
    m[k % R][k] -= 1e-7;
    const double fd = (interlevel_loss({p, w_nerf.detach()}, {s_prop, s_nerf}) -
                       interlevel_loss({m, w_nerf.detach()}, {s_prop, s_nerf}))
                          .item<double>() /
                      2e-7;
    EXPECT_NEAR(w_prop.grad()[k % R][k].item<double>(), fd, 1e-6);
  }
}

TEST(Losses, InterlevelIsZeroWhenTheEnvelopeBoundsTheTarget) {
  const auto s = torch::tensor({{0.0, 0.25, 0.5, 0.75, 1.0}}, torch::kFloat64);
  const auto w = torch::tensor({{0.1, 0.4, 0.3, 0.1}}, torch::kFloat64);
  EXPECT_NEAR(interlevel_loss({w, w}, {s, s}).item<double>(), 0.0, 1e-15);
}

TEST(Losses, DistortionMatchesTheQuadraticDefinition) {
  torch::Generator gen = at::detail::createCPUGenerator(2);
  const auto s = random_edges(3, 9, gen);
  auto w = torch::rand({3, 9}, gen, torch::kFloat64).requires_grad_(true);
  auto w_ref = w.detach().clone().requires_grad_(true);
  const auto fast = distortion_loss(w, s);
  const auto slow = slow_distortion(w_ref, s);
  EXPECT_NEAR(fast.item<double>(), slow.item<double>(), 1e-12);
  fast.backward();
  slow.backward();
  EXPECT_TRUE(torch::allclose(w.grad(), w_ref.grad(), 1e-10, 1e-12));
}

TEST(Losses, DistortionOfASingleDeltaIsItsIntraTerm) {
  // All weight in one interval of width 0.2: loss = w²·0.2/3.
  const auto s = torch::tensor({{0.0, 0.3, 0.5, 1.0}}, torch::kFloat64);
  const auto w = torch::tensor({{0.0, 1.0, 0.0}}, torch::kFloat64);
  EXPECT_NEAR(distortion_loss(w, s).item<double>(), 0.2 / 3, 1e-12);
}
