#include "neraf/dsp/auralize.h"

#include <gtest/gtest.h>

#include <cmath>

#include "neraf/util/error.h"

using neraf::io::AudioBuffer;

namespace {

AudioBuffer make(int rate, std::vector<std::vector<float>> channels) {
  AudioBuffer a;
  a.sample_rate = rate;
  a.channels = std::move(channels);
  return a;
}

}  // namespace

TEST(Auralize, ChannelRules) {
  EXPECT_EQ(neraf::dsp::auralized_channels(2, 1), 2);  // binaural RIR, mono dry
  EXPECT_EQ(neraf::dsp::auralized_channels(1, 1), 1);
  EXPECT_EQ(neraf::dsp::auralized_channels(2, 2), 2);  // channel by channel
  EXPECT_EQ(neraf::dsp::auralized_channels(1, 2), 2);  // every dry channel through the RIR
  EXPECT_EQ(neraf::dsp::auralized_channels(4, 1), 4);
  EXPECT_EQ(neraf::dsp::auralized_channels(2, 3), 0);
  EXPECT_EQ(neraf::dsp::auralized_channels(4, 2), 0);
}

TEST(Auralize, MonoDryThroughBinauralRir) {
  const AudioBuffer rir = make(16000, {{1.0f, 0.0f, 0.5f}, {0.0f, 0.25f, 0.0f}});
  const AudioBuffer dry = make(16000, {{1.0f, 2.0f, 3.0f, 4.0f}});
  const AudioBuffer wet = neraf::dsp::auralize(rir, dry);
  EXPECT_EQ(wet.sample_rate, 16000);
  ASSERT_EQ(wet.num_channels(), 2);
  ASSERT_EQ(wet.num_frames(), 4 + 3 - 1);
  const std::vector<float> left = {1.0f, 2.0f, 3.5f, 5.0f, 1.5f, 2.0f};
  const std::vector<float> right = {0.0f, 0.25f, 0.5f, 0.75f, 1.0f, 0.0f};
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(wet.channels[0][i], left[i], 1e-6) << i;
    EXPECT_NEAR(wet.channels[1][i], right[i], 1e-6) << i;
  }
}

TEST(Auralize, StereoDryWithStereoAndMonoRirs) {
  const AudioBuffer dry = make(8000, {{1.0f, 0.0f}, {0.0f, 1.0f}});
  const AudioBuffer stereo_rir = make(8000, {{0.5f}, {2.0f}});
  AudioBuffer wet = neraf::dsp::auralize(stereo_rir, dry);
  ASSERT_EQ(wet.num_channels(), 2);
  EXPECT_EQ(wet.channels[0], (std::vector<float>{0.5f, 0.0f}));
  EXPECT_EQ(wet.channels[1], (std::vector<float>{0.0f, 2.0f}));
  const AudioBuffer mono_rir = make(8000, {{1.0f, -1.0f}});
  wet = neraf::dsp::auralize(mono_rir, dry);
  ASSERT_EQ(wet.num_channels(), 2);
  EXPECT_EQ(wet.channels[0], (std::vector<float>{1.0f, -1.0f, 0.0f}));
  EXPECT_EQ(wet.channels[1], (std::vector<float>{0.0f, 1.0f, -1.0f}));
}

TEST(Auralize, RejectsMismatches) {
  const AudioBuffer dry3 = make(8000, {{1.0f}, {1.0f}, {1.0f}});
  const AudioBuffer rir2 = make(8000, {{1.0f}, {1.0f}});
  EXPECT_THROW(neraf::dsp::auralize(rir2, dry3), neraf::Error);
  const AudioBuffer dry_other_rate = make(16000, {{1.0f}});
  EXPECT_THROW(neraf::dsp::auralize(rir2, dry_other_rate), neraf::Error);
  EXPECT_THROW(neraf::dsp::auralize(make(8000, {{}}), make(8000, {{1.0f}})), neraf::Error);
}

TEST(Auralize, PeakNormalisationKeepsChannelBalance) {
  AudioBuffer a = make(8000, {{0.5f, -2.0f}, {1.0f, 0.25f}});
  EXPECT_FLOAT_EQ(neraf::dsp::peak_abs(a), 2.0f);
  const float gain = neraf::dsp::normalize_peak(a, 0.99f);
  EXPECT_FLOAT_EQ(gain, 0.495f);
  EXPECT_FLOAT_EQ(a.channels[0][1], -0.99f);
  EXPECT_FLOAT_EQ(a.channels[1][0], 0.495f);
  AudioBuffer silent = make(8000, {{0.0f, 0.0f}});
  EXPECT_FLOAT_EQ(neraf::dsp::normalize_peak(silent), 1.0f);
  EXPECT_EQ(silent.channels[0], (std::vector<float>{0.0f, 0.0f}));
}
