#include "neraf/acoustic/calibration.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

namespace neraf::acoustic {
namespace {

// log(M + 1e-3) of magnitudes M: [N, C, F, T] float32.
torch::Tensor log_of(const torch::Tensor& m) { return torch::log(m + 1e-3).to(torch::kFloat32); }

TEST(EnergyCalibration, BinEnergySumsSquaredMagnitudesOverRirs) {
  // N = 2 RIRs, C = 1, F = 2, T = 2.
  const auto m =
      torch::tensor({1.0, 2.0, 3.0, 0.0, 0.5, 0.0, 0.0, 1.0}, torch::kFloat64).view({2, 1, 2, 2});
  const torch::Tensor e = bin_energy(log_of(m));  // [1, 2, 2]
  ASSERT_EQ(e.sizes(), (std::vector<int64_t>{1, 2, 2}));
  // (f, t) = (0, 0): 1² + 0.5²; (0, 1): 2² + 0²; (1, 0): 3² + 0²; (1, 1): 0² + 1² (float32 logs).
  const double want[2][2] = {{1.25, 4.0}, {9.0, 1.0}};
  for (int f = 0; f < 2; ++f)
    for (int t = 0; t < 2; ++t) EXPECT_NEAR(e[0][f][t].item<double>(), want[f][t], 1e-4);
}

TEST(EnergyCalibration, GainRestoresTheGroundTruthFrameEnergy) {
  // Two RIRs [N = 2, C = 1, F = 1, T = 3]. Frame 0: the prediction has a quarter of the truth's
  // energy (0.5² + 0.5² vs 1² + 1² → gain 2); frame 1 equal; frame 2 silent.
  const auto gt = torch::tensor({1.0, 0.2, 0.0, 1.0, 0.2, 0.0}, torch::kFloat64).view({2, 1, 1, 3});
  const auto pred =
      torch::tensor({0.5, 0.2, 0.0, 0.5, 0.2, 0.0}, torch::kFloat64).view({2, 1, 1, 3});
  const torch::Tensor g = calibration_gain(bin_energy(log_of(gt)), bin_energy(log_of(pred)));
  ASSERT_EQ(g.sizes(), (std::vector<int64_t>{1, 1, 3}));
  EXPECT_NEAR(g[0][0][0].item<float>(), 2.0f, 1e-4);
  EXPECT_NEAR(g[0][0][1].item<float>(), 1.0f, 1e-4);
  EXPECT_EQ(g[0][0][2].item<float>(), 1.0f);  // no energy on either side: unchanged
  const torch::Tensor out = apply_calibration(log_of(pred), g);
  EXPECT_TRUE(torch::allclose(out, log_of(gt), 1e-5, 1e-5));
}

TEST(EnergyCalibration, GainIsClampedAndKeepsShapeAndDtype) {
  const auto gt = torch::full({2, 3, 1}, 1e6, torch::kFloat64);  // [C, F, T]
  const auto pred = torch::full({2, 3, 1}, 1.0, torch::kFloat64);
  const torch::Tensor g = calibration_gain(gt, pred);
  EXPECT_FLOAT_EQ(g[1][2][0].item<float>(), static_cast<float>(kMaxCalibrationGain));
  const torch::Tensor x = torch::zeros({4, 2, 3, 1});  // [N, C, F, T]
  const torch::Tensor y = apply_calibration(x, g);
  EXPECT_EQ(y.sizes(), x.sizes());
  EXPECT_EQ(y.scalar_type(), torch::kFloat32);
  // M = e^0 − 1e-3 = 0.999 → 9.99 + 1e-3 = 9.991.
  EXPECT_NEAR(y[0][0][0][0].item<float>(), std::log(9.991f), 1e-5);
  EXPECT_THROW(apply_calibration(x, torch::ones({2, 1, 1})), c10::Error);
}

TEST(EnergyCalibration, EarlyBalanceScalesTheFramesBeforeTheC50Split) {
  // SoundSpaces: split 1103 samples, hop 128 → frames 0..8 (centre 1024 < 1103) are early.
  const auto gain = torch::full({2, 3, 12}, 0.5);  // [C, F, T]
  const auto delta = torch::tensor({20.0 * std::log10(2.0), -20.0 * std::log10(2.0)},
                                   torch::kFloat64);  // ×2, ×0.5
  const torch::Tensor g = with_early_balance(gain, delta, 128, 1103);
  ASSERT_EQ(g.sizes(), gain.sizes());
  EXPECT_EQ(g.scalar_type(), torch::kFloat32);
  for (int64_t t = 0; t < 12; ++t) {
    EXPECT_NEAR(g[0][1][t].item<float>(), t <= 8 ? 1.0f : 0.5f, 1e-6) << t;
    EXPECT_NEAR(g[1][2][t].item<float>(), t <= 8 ? 0.25f : 0.5f, 1e-6) << t;
  }
  // Clamped like the gains themselves; a split past the last frame scales every frame.
  const auto big = with_early_balance(torch::ones({1, 1, 3}), torch::tensor({60.0}), 128, 10000);
  EXPECT_TRUE(torch::allclose(big, torch::full({1, 1, 3}, kMaxCalibrationGain)));
  EXPECT_THROW(with_early_balance(gain, torch::zeros({3}), 128, 1103), c10::Error);
}

}  // namespace
}  // namespace neraf::acoustic
