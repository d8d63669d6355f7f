#include "neraf/acoustic/losses.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

namespace neraf::acoustic {
namespace {

TEST(AudioLoss, HandComputedScAndSl) {
  // pred log-mags (0, ln 2), gt (ln 3, 0): X = (0.999, 1.999), Y = (2.999, 0.999), Y − X = (2, −1).
  const auto pred = torch::tensor({0.0, std::log(2.0)}, torch::kFloat32).view({1, 1, 2});
  const auto gt = torch::tensor({std::log(3.0), 0.0}, torch::kFloat32).view({1, 1, 2});
  const auto t = spectral_loss(pred, gt);
  const double sc = std::sqrt(5.0) / std::sqrt(2.999 * 2.999 + 0.999 * 0.999);  // 0.7073897
  const double sl = (std::log(3.0) * std::log(3.0) + std::log(2.0) * std::log(2.0)) / 2.0;
  EXPECT_NEAR(t.sc.item<double>(), sc, 1e-6);
  EXPECT_NEAR(t.sc.item<double>(), 0.7073897, 1e-6);
  EXPECT_NEAR(t.sl.item<double>(), sl, 1e-6);
  EXPECT_NEAR(t.sl.item<double>(), 0.8437010, 1e-6);
  EXPECT_NEAR(t.sc_loss.item<double>(), 1e-4 * sc, 1e-10);  // 1e-3 · 0.1
  EXPECT_NEAR(t.mag_loss.item<double>(), 1e-3 * sl, 1e-10);
  EXPECT_NEAR(t.total.item<double>(), 1e-4 * sc + 1e-3 * sl, 1e-10);
}

TEST(AudioLoss, TheLossStudysOtherCriteriaByHand) {
  // The same pair as above: |gt − pred| = (ln 3, ln 2).
  const auto pred = torch::tensor({0.0, std::log(2.0)}, torch::kFloat32).view({1, 1, 2});
  const auto gt = torch::tensor({std::log(3.0), 0.0}, torch::kFloat32).view({1, 1, 2});
  const double sc = 0.7073897;
  AudioLossOptions l1;
  l1.criterion = AudioCriterion::sc_sll1;
  const auto a = spectral_loss(pred, gt, l1);
  const double sl1 = (std::log(3.0) + std::log(2.0)) / 2.0;  // 0.8958797
  EXPECT_NEAR(a.sl.item<double>(), sl1, 1e-6);
  EXPECT_NEAR(a.total.item<double>(), 1e-4 * sc + 1e-3 * sl1, 1e-9);
  AudioLossOptions mse;
  mse.criterion = AudioCriterion::mse;
  const auto b = spectral_loss(pred, gt, mse);
  EXPECT_NEAR(b.sc.item<double>(), sc, 1e-6);  // still reported
  EXPECT_EQ(b.sc_loss.item<double>(), 0.0);
  EXPECT_NEAR(b.total.item<double>(), 1e-3 * 0.8437010, 1e-9);
  EXPECT_EQ(parse_audio_criterion("sc_sll1"), AudioCriterion::sc_sll1);
  EXPECT_EQ(parse_audio_criterion("SC+SLMSE"), std::nullopt);
}

TEST(AudioLoss, ScIsOneRatioOverTheWholeBatch) {
  torch::manual_seed(0);
  const auto pred = torch::randn({4, 2, 9});
  auto gt = torch::randn({4, 2, 9});
  gt[0] += 3.0;  // one loud sample dominates the batch norm
  const auto t = spectral_loss(pred, gt);
  const auto x = torch::exp(pred.to(torch::kFloat64)) - 1e-3;
  const auto y = torch::exp(gt.to(torch::kFloat64)) - 1e-3;
  const double whole = ((y - x).pow(2).sum().sqrt() / y.pow(2).sum().sqrt()).item<double>();
  double per_sample = 0.0;
  for (int b = 0; b < 4; ++b) {
    per_sample += ((y[b] - x[b]).pow(2).sum().sqrt() / y[b].pow(2).sum().sqrt()).item<double>() / 4;
  }
  EXPECT_NEAR(t.sc.item<double>(), whole, 1e-5 * whole);
  EXPECT_GT(std::abs(whole - per_sample), 1e-2);
  // No clipping: pred below log(1e-3) gives a negative X and still counts.
  const auto low = torch::full({1, 1, 1}, -10.0);
  const auto one = torch::zeros({1, 1, 1});
  const double xl = std::exp(-10.0) - 1e-3;  // < 0
  EXPECT_NEAR(spectral_loss(low, one).sc.item<double>(), std::abs(0.999 - xl) / 0.999, 1e-6);
}

TEST(AudioLoss, WeightsAreConfigurableAndGradientFlows) {
  AudioLossOptions o;
  o.loss_factor = 1.0;
  o.sc_weight = 2.0;
  o.mag_weight = 0.5;
  auto pred = torch::zeros({2, 1, 3}, torch::requires_grad());
  const auto gt = torch::ones({2, 1, 3});
  const auto t = spectral_loss(pred, gt, o);
  EXPECT_NEAR(t.mag_loss.item<double>(), 0.5, 1e-6);  // mean((1 − 0)²)·0.5
  EXPECT_NEAR(t.sc_loss.item<double>(), 2.0 * t.sc.item<double>(), 1e-6);
  t.total.backward();
  EXPECT_LT(pred.grad().max().item<float>(), 0.0f);  // raising pred towards gt lowers the loss
}

// One RIR, one channel, F = 2, T = 3, as log-magnitudes log(M + 1e-3) of these magnitudes M.
const double kDecayPred[2][3] = {{1.0, 0.5, 0.25}, {0.0, 0.5, 0.0}};
const double kDecayGt[2][3] = {{2.0, 0.5, 0.1}, {0.0, 0.0, 0.1}};
torch::Tensor decay_log(const double m[2][3]) {
  auto t = torch::empty({1, 1, 2, 3}, torch::kFloat64);
  for (int f = 0; f < 2; ++f)
    for (int k = 0; k < 3; ++k) t[0][0][f][k] = std::log(m[f][k] + 1e-3);
  return t;
}

TEST(EnergyDecayLoss, HandComputed) {
  // One RIR, one channel, F = 2, T = 3. Magnitudes M = exp(L) − 1e-3.
  // E_p = (1, 0.5, 0.0625) → D_p = (1.5625, 0.5625, 0.0625); E_g = (4, 0.25, 0.02) →
  // D_g = (4.27, 0.27, 0.02).
  const double dp[3] = {1.5625, 0.5625, 0.0625}, dg[3] = {4.27, 0.27, 0.02};
  double want = 0;
  for (int k = 0; k < 3; ++k) want += std::abs(std::log10(dp[k]) - std::log10(dg[k])) / 3.0;
  EXPECT_NEAR(energy_decay_loss(decay_log(kDecayPred), decay_log(kDecayGt)).item<double>(), want,
              1e-5);
  EXPECT_NEAR(want, 0.416739, 1e-5);
  EXPECT_NEAR(energy_decay_loss(decay_log(kDecayGt), decay_log(kDecayGt)).item<double>(), 0.0,
              1e-7);
}

TEST(EnergyDecayLoss, FloorIgnoresTheCurveFarBelowTheTotalEnergy) {
  // GT D = (4.27, 0.27, 0.02): a 10 dB floor sits at log10(4.27) − 1 = log10(0.427), so only
  // frame 0 counts (both curves are clamped at the floor for frames 1 and 2).
  // pred D = (1.5625, 0.5625, 0.0625) → clamped (1.5625, 0.5625, 0.427).
  const double want = (std::abs(std::log10(1.5625) - std::log10(4.27)) +
                       std::abs(std::log10(0.5625) - std::log10(0.427))) /
                      3.0;
  EXPECT_NEAR(
      energy_decay_loss(decay_log(kDecayPred), decay_log(kDecayGt), 1e-12, 10.0).item<double>(),
      want, 1e-5);
}

TEST(EnergyDecayLoss, SilentTailStaysFiniteAndDifferentiable) {
  auto pred = torch::full({2, 1, 4, 5}, std::log(1e-3), torch::requires_grad());  // M = 0
  const auto gt = torch::zeros({2, 1, 4, 5});
  const auto l = energy_decay_loss(pred, gt);
  EXPECT_TRUE(std::isfinite(l.item<double>()));
  l.backward();
  EXPECT_TRUE(torch::isfinite(pred.grad()).all().item<bool>());
  EXPECT_THROW(energy_decay_loss(torch::zeros({2, 4, 5}), torch::zeros({2, 4, 5})), std::exception);
}

}  // namespace
}  // namespace neraf::acoustic
