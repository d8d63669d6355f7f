#include "neraf/nerf/samplers.h"

#include <ATen/CPUGeneratorImpl.h>
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

using namespace neraf::nerf;

namespace {
bool sorted_rows(const torch::Tensor& t) {
  return (t.slice(1, 1) >= t.slice(1, 0, -1)).all().item<bool>();
}
}  // namespace

TEST(Samplers, SpacingFunctionAndInverse) {
  const auto t = torch::tensor({0.0, 0.5, 1.0, 2.0, 10.0}, torch::kFloat64);
  const auto s = lindisp_piecewise_spacing(t);
  const auto want = torch::tensor({0.0, 0.25, 0.5, 0.75, 0.95}, torch::kFloat64);
  EXPECT_TRUE(torch::allclose(s, want));
  EXPECT_TRUE(torch::allclose(lindisp_piecewise_spacing_inv(s), t));
}

TEST(Samplers, UniformLinDispEvalEdgesFollowTheSpacingRule) {
  const auto nears = torch::full({2}, 0.05f), fars = torch::full({2}, 1000.0f);
  const RaySamples r = uniform_lindisp_samples(nears, fars, 8, false, true, nullptr);
  ASSERT_EQ(r.sdist.sizes(), (std::vector<int64_t>{2, 9}));
  // Eval: spacing edges are exactly linspace(0, 1, 9).
  EXPECT_TRUE(torch::allclose(r.sdist[0], torch::linspace(0, 1, 9)));
  EXPECT_NEAR(r.tdist[0][0].item<float>(), 0.05f, 1e-6);
  EXPECT_NEAR(r.tdist[0][8].item<float>(), 1000.0f, 0.5f);
  // Edge k: t = g⁻¹(s g(far) + (1 − s) g(near)), g(near) = 0.025, g(far) = 0.9995.
  for (int k = 0; k < 9; ++k) {
    const double s = k / 8.0, g = s * 0.9995 + (1 - s) * 0.025;
    const double t = g < 0.5 ? 2 * g : 0.5 / (1 - g);
    EXPECT_NEAR(r.tdist[1][k].item<float>(), t, 1e-4 * std::max(1.0, t)) << k;
  }
}

TEST(Samplers, JitteredSamplesAreSortedInsideNearFarAndOneOffsetPerRay) {
  auto gen = at::make_generator<at::CPUGeneratorImpl>(7);
  const auto nears = torch::full({64}, 0.05f), fars = torch::full({64}, 6.0f);
  const RaySamples r = uniform_lindisp_samples(nears, fars, 16, true, true, &gen);
  EXPECT_TRUE(sorted_rows(r.sdist));
  EXPECT_TRUE(sorted_rows(r.tdist));
  EXPECT_GE(r.tdist.min().item<float>(), 0.05f - 1e-6f);
  EXPECT_LE(r.tdist.max().item<float>(), 6.0f + 1e-4f);
  // Single jitter: interior edges all sit at the same fraction t_rand between the two bin
  // centres around them, i.e. edge_k = (k − ½ + t_rand)/16 for k = 1..15.
  const auto interior = r.sdist.slice(1, 1, 16) * 16.0 - torch::arange(1, 16).to(torch::kFloat32);
  const auto spread = interior.amax(1) - interior.amin(1);
  EXPECT_LT(spread.max().item<float>(), 1e-4f);
  EXPECT_GE(interior.min().item<float>(), -0.5f - 1e-5f);
  EXPECT_LE(interior.max().item<float>(), 0.5f + 1e-5f);
  // Different rays get different offsets.
  EXPECT_GT((interior.select(1, 0).max() - interior.select(1, 0).min()).item<float>(), 0.1f);
}

TEST(Samplers, PdfSamplesConcentrateWhereTheWeightIs) {
  auto gen = at::make_generator<at::CPUGeneratorImpl>(3);
  const int64_t R = 32;
  const auto nears = torch::full({R}, 0.05f), fars = torch::full({R}, 1000.0f);
  const RaySamples coarse = uniform_lindisp_samples(nears, fars, 64, false, true, nullptr);
  auto w = torch::zeros({R, 64});
  w.slice(1, 20, 22).fill_(0.5f);  // all mass in spacing [20/64, 22/64]
  for (bool stratified : {false, true}) {
    const RaySamples fine = pdf_samples(coarse, w, nears, fars, 32, stratified, true, 0.01, 1e-5,
                                        &gen);
    ASSERT_EQ(fine.sdist.sizes(), (std::vector<int64_t>{R, 33}));
    EXPECT_TRUE(sorted_rows(fine.sdist));
    EXPECT_GE(fine.tdist.min().item<float>(), 0.05f - 1e-6f);
    EXPECT_LE(fine.tdist.max().item<float>(), 1000.0f * (1 + 1e-4f));
    // Padding 0.01 per bin (64 × 0.01 = 0.64 of total 1.64) → ≈ 61 % of the samples land in the
    // weighted bins.
    const auto in_peak = ((fine.sdist >= 20.0 / 64) & (fine.sdist <= 22.0 / 64)).to(torch::kFloat32);
    const float frac = in_peak.mean().item<float>();
    EXPECT_NEAR(frac, 1.0 / 1.64, 0.05) << "stratified=" << stratified;
  }
  // Eval midpoints are deterministic.
  const RaySamples a = pdf_samples(coarse, w, nears, fars, 32, false, true, 0.01, 1e-5, nullptr);
  const RaySamples b = pdf_samples(coarse, w, nears, fars, 32, false, true, 0.01, 1e-5, nullptr);
  EXPECT_TRUE(torch::equal(a.sdist, b.sdist));
}

TEST(Samplers, PdfOfUniformWeightsReproducesUniformSpacing) {
  const auto nears = torch::full({1}, 0.05f), fars = torch::full({1}, 1000.0f);
  const RaySamples coarse = uniform_lindisp_samples(nears, fars, 16, false, true, nullptr);
  const RaySamples fine = pdf_samples(coarse, torch::full({1, 16}, 1.0f / 16), nears, fars, 7,
                                      false, true, 0.01, 1e-5, nullptr);
  // Midpoint positions u_k = (k + ½)/8 of a uniform cdf.
  const auto want = (torch::arange(8).to(torch::kFloat32) + 0.5f) / 8.0f;
  EXPECT_TRUE(torch::allclose(fine.sdist[0], want, 1e-5, 1e-5));
}

TEST(Samplers, AllZeroWeightsStayFinite) {
  const auto nears = torch::full({2}, 0.05f), fars = torch::full({2}, 1000.0f);
  const RaySamples coarse = uniform_lindisp_samples(nears, fars, 8, false, true, nullptr);
  const RaySamples fine = pdf_samples(coarse, torch::zeros({2, 8}), nears, fars, 8, false, true,
                                      0.0, 1e-5, nullptr);
  EXPECT_TRUE(torch::isfinite(fine.sdist).all().item<bool>());
  EXPECT_TRUE(sorted_rows(fine.sdist));
}

TEST(Samplers, WeightAnnealValues) {
  EXPECT_DOUBLE_EQ(proposal_weight_anneal(0, 10, 1000), 0.0);
  EXPECT_NEAR(proposal_weight_anneal(100, 10, 1000), 1.0 / 1.9, 1e-12);
  EXPECT_NEAR(proposal_weight_anneal(500, 10, 1000), 5.0 / 5.5, 1e-12);
  EXPECT_DOUBLE_EQ(proposal_weight_anneal(1000, 10, 1000), 1.0);
  EXPECT_DOUBLE_EQ(proposal_weight_anneal(50000, 10, 1000), 1.0);
}

TEST(Samplers, ProposalUpdateSchedule) {
  int64_t counter = 0;
  std::vector<int64_t> updates;
  for (int64_t step = 0; step < 6000; ++step) {
    const ProposalUpdate u = proposal_update(step, counter, 5, 5000);
    counter = u.steps_since_update;
    if (u.update) updates.push_back(step);
  }
  // Steps 0..9 always update; then every 2nd step while sched = 1 (counter must exceed 1).
  for (int64_t s = 0; s < 10; ++s) EXPECT_EQ(updates[s], s);
  EXPECT_EQ(updates[10], 11);
  EXPECT_EQ(updates[11], 13);
  // Steady state after the 5000-step warm-up: counter must exceed 5 → every 6th step.
  const size_t n = updates.size();
  EXPECT_EQ(updates[n - 1] - updates[n - 2], 6);
  EXPECT_EQ(updates[n - 2] - updates[n - 3], 6);
  // Mid warm-up (sched = 2.5 at step 2500): counter 3 > 2.5 → every 3rd step.
  auto it = std::lower_bound(updates.begin(), updates.end(), 2500);
  EXPECT_EQ(*(it + 1) - *it, 3);
}
