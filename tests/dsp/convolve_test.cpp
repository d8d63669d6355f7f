#include "neraf/dsp/convolve.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

std::vector<float> random_vector(size_t n, std::mt19937& gen) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> x(n);
  for (float& v : x) v = u(gen);
  return x;
}

std::vector<double> direct(const std::vector<float>& a, const std::vector<float>& b) {
  std::vector<double> y(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) y[i + j] += double(a[i]) * b[j];
  }
  return y;
}

}  // namespace

TEST(FftConvolve, MatchesDirectSummation) {
  std::mt19937 gen(1);
  std::uniform_int_distribution<size_t> len(1, 3000);
  // Fixed edge cases first (length 1, both paths around the direct/FFT switch), then random.
  std::vector<std::pair<size_t, size_t>> sizes = {
      {1, 1},     {1, 500},   {500, 1},     {2, 3},      {32, 32},     {33, 33},
      {33, 4000}, {4000, 40}, {1024, 1024}, {997, 1409}, {40000, 700}, {700, 40001}};
  for (int i = 0; i < 20; ++i) sizes.emplace_back(len(gen), len(gen));
  for (auto [na, nb] : sizes) {
    const auto a = random_vector(na, gen), b = random_vector(nb, gen);
    const auto y = neraf::dsp::fft_convolve(a, b);
    const auto r = direct(a, b);
    ASSERT_EQ(y.size(), na + nb - 1) << na << " x " << nb;
    // Float FFT error grows with the norms, not with each output sample.
    const double tol = 1e-6 * std::sqrt(double(na) * double(nb)) + 1e-6;
    for (size_t i = 0; i < y.size(); ++i)
      ASSERT_NEAR(y[i], r[i], tol) << na << " x " << nb << " at " << i;
  }
}

TEST(FftConvolve, DiracIsIdentityAndEmptyGivesEmpty) {
  std::mt19937 gen(2);
  const auto x = random_vector(5000, gen);
  std::vector<float> d(100, 0.0f);
  d[7] = 1.0f;
  const auto y = neraf::dsp::fft_convolve(x, d);
  ASSERT_EQ(y.size(), 5099u);
  for (size_t i = 0; i < 7; ++i) EXPECT_NEAR(y[i], 0.0f, 1e-6);
  for (size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(y[i + 7], x[i], 1e-5);
  EXPECT_TRUE(neraf::dsp::fft_convolve({}, x).empty());
}
