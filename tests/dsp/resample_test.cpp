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

// ceil(n · to / from), as librosa's fix_length after soxr (hand-computed).
TEST(Resample, LengthIsCeilOfTheRatio) {
  struct Case {
    size_t n;
    double from, to;
    size_t expected;
  };
  for (const Case& c :
       {Case{1, 44100, 22050, 1}, Case{1, 44100, 48000, 2}, Case{1, 48000, 22050, 1},
        Case{3, 44100, 22050, 2}, Case{3, 44100, 48000, 4}, Case{3, 48000, 22050, 2},
        Case{44100, 44100, 22050, 22050}, Case{44100, 44100, 48000, 48000},
        Case{44100, 48000, 22050, 20259}, Case{44101, 44100, 22050, 22051},
        Case{44101, 44100, 48000, 48002}, Case{44101, 48000, 22050, 20259}}) {
    EXPECT_EQ(neraf::dsp::resample(std::vector<float>(c.n, 0.1f), c.from, c.to).size(), c.expected)
        << c.n << " samples " << c.from << " -> " << c.to;
  }
  EXPECT_TRUE(neraf::dsp::resample(std::vector<float>{}, 44100, 22050).empty());
}

// The filter's delay is compensated: an impulse at 1000 / 44100 s peaks at 500 / 22050 s.
TEST(Resample, ImpulseStaysInPlace) {
  std::vector<float> x(4410, 0.0f);
  x[1000] = 1.0f;
  const auto y = neraf::dsp::resample(x, 44100, 22050);
  size_t peak = 0;
  for (size_t i = 0; i < y.size(); ++i)
    if (std::abs(y[i]) > std::abs(y[peak])) peak = i;
  EXPECT_EQ(peak, 500u);
  EXPECT_NEAR(y[peak], 0.5f, 0.05f);  // half the energy is above the new Nyquist frequency
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
