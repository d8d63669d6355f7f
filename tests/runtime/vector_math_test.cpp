#include "neraf/runtime/vector_math.h"

#include <gtest/gtest.h>

#include <cmath>

#include "neraf/runtime/input_encoding.h"

using neraf::rt::exp_approx;
using neraf::rt::log_approx;
using neraf::rt::tanh_approx;

TEST(VectorMath, ExpRelativeErrorBelow1e7) {
  double worst = 0;
  for (float x = -87.0f; x < 88.0f; x += 1.3e-3f)
    worst = std::max(worst, std::fabs(exp_approx(x) - std::exp(double(x))) / std::exp(double(x)));
  EXPECT_LT(worst, 1e-7);
}

TEST(VectorMath, LogAbsoluteErrorBelow6e7) {
  double worst = 0;
  for (float x = 1e-6f; x < 1e5f; x *= 1.00003f)
    worst = std::max(worst, std::fabs(log_approx(x) - std::log(double(x))));
  EXPECT_LT(worst, 6e-7);
}

TEST(VectorMath, TanhAbsoluteErrorBelow1p5e7) {
  double worst = 0;
  for (float x = -20.0f; x < 20.0f; x += 1.7e-4f)
    worst = std::max(worst, std::fabs(tanh_approx(x) - std::tanh(double(x))));
  EXPECT_LT(worst, 1.5e-7);
  EXPECT_EQ(tanh_approx(0.0f), 0.0f);
  EXPECT_FLOAT_EQ(tanh_approx(1e-30f), 1e-30f);
  EXPECT_EQ(tanh_approx(30.0f), 1.0f);
  EXPECT_EQ(tanh_approx(-30.0f), -1.0f);
}

// Found by fuzz/fuzz_c_api: a model whose finite weights overflow to inf - inf gives NaN
// activations, and exp_approx converted NaN to int32 (undefined behaviour, UBSan's
// float-cast-overflow). NaN must come out as NaN.
TEST(VectorMath, NanGivesNan) {
  const float nan = std::nanf("");
  EXPECT_TRUE(std::isnan(exp_approx(nan)));
  EXPECT_TRUE(std::isnan(exp_approx(-nan)));
  EXPECT_TRUE(std::isnan(tanh_approx(nan)));
  EXPECT_EQ(exp_approx(-1e30f), exp_approx(-87.0f));  // the clamps themselves are unchanged
  EXPECT_EQ(exp_approx(1e30f), exp_approx(88.0f));
}

TEST(InputEncoding, FrequenciesAreTorchsFloat32Ones) {
  const auto f = neraf::rt::encoding_frequencies(8.0);
  EXPECT_EQ(f[0], 1.0f);
  EXPECT_EQ(f[9], 256.0f);
  for (int k = 0; k < 10; ++k) EXPECT_NEAR(f[k], std::pow(2.0, 8.0 * k / 9), 2e-7 * f[k]) << k;
}

TEST(InputEncoding, PositionsOutsideOrOnTheBoxBecomeZero) {
  const std::array<double, 3> lo{0, 0, 0}, hi{2, 4, 8};
  const double inside[3] = {1, 1, 2}, face[3] = {0, 1, 2}, out[3] = {1, 5, 2};
  EXPECT_EQ(neraf::rt::normalize_position(inside, lo, hi), (std::array<double, 3>{0.5, 0.25, 0.25}));
  EXPECT_EQ(neraf::rt::normalize_position(face, lo, hi), (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(neraf::rt::normalize_position(out, lo, hi), (std::array<double, 3>{0, 0, 0}));
}
