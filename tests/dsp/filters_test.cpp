#include "neraf/dsp/filters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "neraf/util/error.h"

namespace {

// The RBJ high-pass and the difference equation, written out in double precision:
// a0·y[n] = b0·x[n] + b1·x[n−1] + b2·x[n−2] − a1·y[n−1] − a2·y[n−2], zero initial state.
std::vector<double> reference_highpass(const std::vector<float>& x, double fs, double fc,
                                       double q) {
  const double w0 = 2 * M_PI * fc / fs, alpha = std::sin(w0) / (2 * q), c = std::cos(w0);
  const double b0 = (1 + c) / 2, b1 = -(1 + c), b2 = b0, a0 = 1 + alpha, a1 = -2 * c,
               a2 = 1 - alpha;
  std::vector<double> y(x.size());
  for (size_t n = 0; n < x.size(); ++n) {
    const double xn1 = n >= 1 ? x[n - 1] : 0.0, xn2 = n >= 2 ? x[n - 2] : 0.0;
    const double yn1 = n >= 1 ? y[n - 1] : 0.0, yn2 = n >= 2 ? y[n - 2] : 0.0;
    y[n] = (b0 * x[n] + b1 * xn1 + b2 * xn2 - a1 * yn1 - a2 * yn2) / a0;
  }
  return y;
}

// Steady-state gain of the filter on a sine: RMS of the second half, output over input.
double sine_gain_db(double freq, double fs) {
  const size_t n = static_cast<size_t>(fs);  // 1 s
  std::vector<float> x(n);
  for (size_t i = 0; i < n; ++i)
    x[i] = 0.5f * static_cast<float>(std::sin(2 * M_PI * freq * i / fs));
  const auto y = neraf::dsp::highpass_biquad(x, fs, 200.0);
  double ex = 0.0, ey = 0.0;
  for (size_t i = n / 2; i < n; ++i) {
    ex += double(x[i]) * x[i];
    ey += double(y[i]) * y[i];
  }
  return 10.0 * std::log10(ey / ex);
}

}  // namespace

TEST(HighpassBiquad, MatchesTheDifferenceEquation) {
  std::mt19937 gen(1);
  std::normal_distribution<float> g(0.0f, 0.1f);  // small: the output clamp never engages
  std::vector<float> x(20000);
  for (float& v : x) v = g(gen);
  for (double fs : {22050.0, 48000.0}) {
    const auto y = neraf::dsp::highpass_biquad(x, fs, 200.0, 0.707);
    const auto r = reference_highpass(x, fs, 200.0, 0.707);
    ASSERT_EQ(y.size(), r.size());
    for (size_t i = 0; i < y.size(); ++i)
      ASSERT_NEAR(y[i], r[i], 2e-5) << "fs " << fs << " i " << i;
  }
}

TEST(HighpassBiquad, ClampsTheOutputNotTheState) {
  // A loud step: the unclamped response overshoots ±1 at the edges; torchaudio clamps only the
  // final output, so every sample equals clamp(reference).
  std::vector<float> x(4000, 0.0f);
  for (size_t i = 1000; i < 3000; ++i) x[i] = 1.8f;
  const auto y = neraf::dsp::highpass_biquad(x, 48000.0, 200.0);
  const auto r = reference_highpass(x, 48000.0, 200.0, 0.707);
  bool clamped = false;
  for (size_t i = 0; i < y.size(); ++i) {
    clamped |= std::abs(r[i]) > 1.0;
    ASSERT_NEAR(y[i], std::clamp(r[i], -1.0, 1.0), 1e-4) << i;  // float32 filter, amplitude 1.8
  }
  EXPECT_TRUE(clamped) << "the test signal should exceed the clamp";
}

TEST(HighpassBiquad, FrequencyResponse) {
  // Second-order high-pass at 200 Hz: about −24 dB two octaves below, flat well above.
  EXPECT_LT(sine_gain_db(50.0, 48000.0), -20.0);
  EXPECT_NEAR(sine_gain_db(2000.0, 48000.0), 0.0, 0.1);
  EXPECT_NEAR(sine_gain_db(200.0, 48000.0), -3.0, 0.3);  // −3 dB at the cutoff for Q = 0.707
  EXPECT_LT(sine_gain_db(50.0, 22050.0), -20.0);
}

TEST(HighpassBiquad, RejectsBadArguments) {
  const std::vector<float> x(10, 0.1f);
  EXPECT_THROW(neraf::dsp::highpass_biquad(x, 0.0, 200.0), neraf::Error);
  EXPECT_THROW(neraf::dsp::highpass_biquad(x, 16000.0, 9000.0), neraf::Error);
  EXPECT_TRUE(neraf::dsp::highpass_biquad({}, 16000.0, 200.0).empty());
}
