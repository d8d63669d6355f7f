#include "neraf/dsp/resample.h"

#include <gtest/gtest.h>

#include <cmath>

#include "neraf/util/error.h"

namespace {

std::vector<float> sine(double freq, double fs, size_t n, double amp = 0.5) {
  std::vector<float> x(n);
  for (size_t i = 0; i < n; ++i)
    x[i] = static_cast<float>(amp * std::sin(2 * M_PI * freq * i / fs));
  return x;
}

// RMS of the middle half (away from the filter's start-up and flush at the ends).
double middle_rms(const std::vector<float>& x) {
  double e = 0.0;
  const size_t a = x.size() / 4, b = 3 * x.size() / 4;
  for (size_t i = a; i < b; ++i) e += double(x[i]) * x[i];
  return std::sqrt(e / double(b - a));
}

}  // namespace

TEST(Resample, PassbandSineKeepsItsAmplitude) {
  const auto x = sine(1000.0, 44100.0, 44100);
  const auto y = neraf::dsp::resample(x, 44100.0, 22050.0);
  const double db = 20.0 * std::log10(middle_rms(y) / middle_rms(x));
  EXPECT_LT(std::abs(db), 0.1) << db << " dB";
  // And it is still the same sine, in phase (libsamplerate compensates its delay).
  const auto expected = sine(1000.0, 22050.0, y.size());
  for (size_t i = y.size() / 4; i < 3 * y.size() / 4; ++i)
    ASSERT_NEAR(y[i], expected[i], 1e-3) << i;
}

TEST(Resample, AboveNewNyquistIsRemoved) {
  const auto x = sine(15000.0, 44100.0, 44100);
  const auto y = neraf::dsp::resample(x, 44100.0, 22050.0);
  const double db = 20.0 * std::log10(middle_rms(y) / middle_rms(x));
  EXPECT_LT(db, -60.0) << db << " dB";
}

TEST(Resample, LengthIsRoundedRatio) {
  for (size_t n : {size_t(1), size_t(2), size_t(3), size_t(1001), size_t(44100), size_t(44101)}) {
    EXPECT_EQ(neraf::dsp::resample(std::vector<float>(n, 0.1f), 44100, 22050).size(),
              size_t(std::llround(n * 0.5)))
        << n;
    EXPECT_EQ(neraf::dsp::resample(std::vector<float>(n, 0.1f), 44100, 48000).size(),
              size_t(std::llround(n * 48000.0 / 44100.0)))
        << n;
    EXPECT_EQ(neraf::dsp::resample(std::vector<float>(n, 0.1f), 48000, 22050).size(),
              size_t(std::llround(n * 22050.0 / 48000.0)))
        << n;
  }
  EXPECT_TRUE(neraf::dsp::resample(std::vector<float>{}, 44100, 22050).empty());
}

TEST(Resample, SameRateIsIdentityAndBuffersKeepChannels) {
  const auto x = sine(440.0, 48000.0, 1000);
  EXPECT_EQ(neraf::dsp::resample(x, 48000, 48000), x);
  neraf::io::AudioBuffer a;
  a.sample_rate = 44100;
  a.channels = {sine(1000.0, 44100.0, 4410), sine(2000.0, 44100.0, 4410, 0.25)};
  const auto b = neraf::dsp::resample(a, 48000);
  EXPECT_EQ(b.sample_rate, 48000);
  ASSERT_EQ(b.num_channels(), 2);
  EXPECT_EQ(b.num_frames(), 4800);
  EXPECT_EQ(b.channels[1], neraf::dsp::resample(a.channels[1], 44100, 48000));
  EXPECT_THROW(neraf::dsp::resample(x, 0.0, 48000.0), neraf::Error);
  EXPECT_THROW(neraf::dsp::resample(x, 48000.0, 100.0), neraf::Error);  // ratio beyond 1:256
}
