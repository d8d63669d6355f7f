// T60 / EDT / C50 against analytic signals and against the reference values of the real CC0
// recordings (assets/real/README.md).
#include "neraf/metrics/room_acoustics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "neraf/dsp/filters.h"
#include "neraf/io/audio_file.h"
#include "neraf/util/error.h"

namespace neraf::metrics {
namespace {

// White noise whose energy falls 60 dB every `t60` seconds (amplitude ×10^(−3 t / t60)).
std::vector<float> decaying_noise(double t60, double fs, double seconds, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  const size_t n = static_cast<size_t>(seconds * fs);
  std::vector<float> h(n);
  for (size_t i = 0; i < n; ++i) h[i] = u(rng) * float(std::pow(10.0, -3.0 * (i / fs) / t60));
  return h;
}

// h[n] = exp(−a n), n < N: energy r^n with r = exp(−2a), so the Schroeder curve is
// E_dB[n] = 10 log10((r^n − r^N) / (1 − r^N)) and the first index strictly below L dB is the
// smallest n > ln(10^(L/10)·(1 − r^N) + r^N) / ln r.
struct ExactDecay {
  double a;
  size_t n;

  std::vector<float> signal() const {
    std::vector<float> h(n);
    for (size_t i = 0; i < n; ++i) h[i] = float(std::exp(-a * double(i)));
    return h;
  }
  long first_below(double level_db) const {
    const double r = std::exp(-2.0 * a), rn = std::pow(r, double(n));
    const double x = std::log(std::pow(10.0, level_db / 10.0) * (1.0 - rn) + rn) / std::log(r);
    // Stay away from exact ties so float rounding cannot decide the answer.
    EXPECT_GT(std::abs(x - std::round(x)), 1e-3) << "pick another decay: tie at " << x;
    return static_cast<long>(std::floor(x)) + 1;
  }
};

TEST(Schroeder, CurveIsNormalisedAndDropsTheLastNonzeroSample) {
  // Energies 4, 1, 0 (and trailing zeros): E = [5, 1, 0, 0] -> last nonzero index 1, kept [0, 1).
  const std::vector<double> c = schroeder_curve_db({2.0f, 1.0f, 0.0f, 0.0f});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_DOUBLE_EQ(c[0], 0.0);
  const std::vector<double> d = schroeder_curve_db({2.0f, 1.0f, 1.0f, 0.0f});  // E = 6, 2, 1
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NEAR(d[1], 10.0 * std::log10(2.0 / 6.0), 1e-12);
  EXPECT_TRUE(schroeder_curve_db({0.0f, 0.0f}).empty());
  EXPECT_TRUE(schroeder_curve_db({1.0f, 0.0f, 0.0f}).empty());           // only sample 0 has energy
  EXPECT_EQ(first_index_below({0.0, -4.0, -5.0, -5.5, -7.0}, -5.0), 3);  // strictly below
  EXPECT_EQ(first_index_below({0.0, -1.0}, -5.0), -1);
}

TEST(T60, DecayingNoiseMatchesItsDesignedDecay) {
  const double fs = 22050, t60 = 0.5;
  for (uint32_t seed : {1u, 2u, 3u}) {
    const auto h = decaying_noise(t60, fs, 1.2, seed);
    const DecayTime ss = measure_t60(h, fs, Variant::soundspaces);
    ASSERT_TRUE(ss.valid());
    EXPECT_NEAR(ss.seconds, t60, 0.03 * t60) << "seed " << seed;
    const DecayTime raf = measure_t60(h, fs, Variant::raf);
    ASSERT_TRUE(raf.valid());
    EXPECT_NEAR(raf.seconds, t60, 0.03 * t60) << "seed " << seed;
    // A pure exponential decay has EDT = T60.
    EXPECT_NEAR(measure_edt(h, fs).seconds, t60, 0.05 * t60) << "seed " << seed;
  }
}

TEST(T60, ExactExponentialGivesTheClosedFormIndices) {
  const double fs = 22050;
  // 48 dB of total energy decay: the finite tail bends the curve measurably.
  const ExactDecay d{0.0012, 4600};
  const auto h = d.signal();
  for (double decay : {30.0, 10.0}) {
    const long i5 = d.first_below(-5.0), iD = d.first_below(-5.0 - decay);
    const DecayTime t = measure_t60(h, fs, decay);
    ASSERT_TRUE(t.valid());
    EXPECT_DOUBLE_EQ(t.seconds, (60.0 / decay) * (double(iD) / fs - double(i5) / fs));
  }
}

TEST(Edt, ExactExponentialGivesTheClosedFormIndex) {
  for (const ExactDecay& d :
       {ExactDecay{0.0012, 4600}, ExactDecay{0.00053, 30000}, ExactDecay{0.0029, 900}}) {
    const double fs = 48000;
    const DecayTime edt = measure_edt(d.signal(), fs);
    ASSERT_TRUE(edt.valid());
    EXPECT_DOUBLE_EQ(edt.seconds, 6.0 * (double(d.first_below(-10.0)) / fs));
  }
}

TEST(T60, InvalidWhenSilentOrDecayTooShort) {
  const double fs = 22050;
  const std::vector<float> zeros(5000, 0.0f);
  EXPECT_EQ(measure_t60(zeros, fs, Variant::soundspaces).status, DecayStatus::silent);
  EXPECT_EQ(measure_t60(zeros, fs, Variant::raf).status, DecayStatus::silent);
  EXPECT_EQ(measure_t60({}, fs, 30.0).status, DecayStatus::silent);
  EXPECT_EQ(measure_t60(zeros, fs, Variant::soundspaces).reference_t60(), -1.0);

  // A constant signal of 1000 samples: the Schroeder curve is 10 log10((1000 − n) / 1000), which
  // ends at 10 log10(2/1000) = −27 dB (the last sample is dropped): RAF's −15 dB is reached,
  // SoundSpaces' −35 dB never.
  const std::vector<float> shallow(1000, 0.3f);
  const DecayTime ss = measure_t60(shallow, fs, 30.0);
  EXPECT_EQ(ss.status, DecayStatus::no_decay);
  EXPECT_FALSE(ss.valid());
  EXPECT_EQ(ss.reference_t60(), -1.0);
  const DecayTime raf = measure_t60(shallow, fs, 10.0);
  ASSERT_TRUE(raf.valid());
  // First n with (1000 − n)/1000 below 10^-0.5 is 684, below 10^-1.5 is 969.
  EXPECT_DOUBLE_EQ(raf.seconds, 6.0 * (969.0 / fs - 684.0 / fs));

  // A lone impulse: only sample 0 has energy, the reference's truncated curve is empty.
  std::vector<float> impulse(100, 0.0f);
  impulse[0] = 1.0f;
  EXPECT_EQ(measure_t60(impulse, fs, 30.0).status, DecayStatus::no_decay);
}

TEST(Edt, InvalidWhenSilentOrNeverAtMinus10Db) {
  const DecayTime silent = measure_edt(std::vector<float>(300, 0.0f), 22050);
  EXPECT_EQ(silent.status, DecayStatus::silent);
  EXPECT_TRUE(std::isnan(silent.reference_edt()));
  const std::vector<float> flat(300, 0.3f);  // linear energy ramp: −10 dB only near the end
  const std::vector<float> two = {1.0f, 1.0f};
  EXPECT_TRUE(measure_edt(flat, 22050).valid());
  EXPECT_EQ(measure_edt(two, 22050).status, DecayStatus::no_decay);
}

TEST(C50, SplitSampleIsTheReferenceIndex) {
  EXPECT_EQ(c50_split_sample(22050), 1103);
  EXPECT_EQ(c50_split_sample(48000), 2401);
  EXPECT_EQ(c50_split_sample(44100), 2206);
  EXPECT_EQ(c50_split_sample(16000), 801);
}

TEST(C50, KnownEnergySplit) {
  const double fs = 22050;
  const long t = c50_split_sample(fs);
  // Amplitude 2 before the split, 1 after, equal lengths: energy ratio 4 -> 6.0206 dB.
  std::vector<float> h(2 * t, 1.0f);
  for (long i = 0; i < t; ++i) h[i] = 2.0f;
  EXPECT_NEAR(measure_c50(h, fs), 10.0 * std::log10(4.0), 1e-12);
  // Ones with 3t samples after the split: 10 log10(1/3).
  std::vector<float> ones(4 * t, 1.0f);
  EXPECT_NEAR(measure_c50(ones, fs), 10.0 * std::log10(1.0 / 3.0), 1e-12);
}

TEST(C50, ZeroEnergyFollowsIeeeLikeTheReference) {
  const double fs = 22050;
  const long t = c50_split_sample(fs);
  EXPECT_TRUE(std::isnan(measure_c50(std::vector<float>(3 * t, 0.0f), fs)));
  std::vector<float> early_only(3 * t, 0.0f);
  early_only[5] = 0.5f;
  EXPECT_EQ(measure_c50(early_only, fs), std::numeric_limits<double>::infinity());
  std::vector<float> late_only(3 * t, 0.0f);
  late_only[t + 5] = 0.5f;
  EXPECT_EQ(measure_c50(late_only, fs), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(measure_c50(std::vector<float>(10, 1.0f), fs),  // shorter than the split
            std::numeric_limits<double>::infinity());
}

TEST(Variant, RafHighPassesOnlyTheT60) {
  const double fs = 22050;
  // A loud 40 Hz tone that rings for long plus noise that dies fast: the full-band curve follows
  // the tone, the 200 Hz high-passed one the noise.
  const size_t n = static_cast<size_t>(1.5 * fs);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.3f, 0.3f);
  std::vector<float> h(n);
  for (size_t i = 0; i < n; ++i) {
    const double t = i / fs;
    h[i] = float(0.5 * std::sin(2 * M_PI * 40 * t) * std::pow(10.0, -3.0 * t / 1.2) +
                 u(rng) * std::pow(10.0, -3.0 * t / 0.3));
  }
  const std::vector<float> hp = dsp::highpass_biquad(h, fs, 200.0, 0.707);
  const DecayTime raf = measure_t60(h, fs, Variant::raf);
  const DecayTime manual = measure_t60(hp, fs, 10.0);
  ASSERT_TRUE(raf.valid());
  EXPECT_DOUBLE_EQ(raf.seconds, manual.seconds);
  EXPECT_GT(std::abs(raf.seconds - measure_t60(h, fs, 10.0).seconds), 0.1);  // filter matters

  io::AudioBuffer buf{int(fs), {h}};
  const auto a = measure_room_acoustics(buf, Variant::raf);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_DOUBLE_EQ(a[0].t60.seconds, manual.seconds);
  EXPECT_DOUBLE_EQ(a[0].edt.seconds, measure_edt(h, fs).seconds);  // raw signal
  EXPECT_DOUBLE_EQ(a[0].c50_db, measure_c50(h, fs));               // raw signal
  // ... and the high-pass would have changed them, so the test can tell.
  EXPECT_NE(measure_edt(hp, fs).seconds, measure_edt(h, fs).seconds);
  EXPECT_NE(measure_c50(hp, fs), measure_c50(h, fs));
  const auto s = measure_room_acoustics(buf, Variant::soundspaces);
  EXPECT_DOUBLE_EQ(s[0].t60.seconds, measure_t60(h, fs, 30.0).seconds);
}

TEST(Variant, NamesAndParameters) {
  EXPECT_EQ(parse_variant("raf"), Variant::raf);
  EXPECT_EQ(parse_variant("soundspaces"), Variant::soundspaces);
  EXPECT_THROW(parse_variant("RAF"), Error);
  EXPECT_EQ(to_string(Variant::raf), "raf");
  EXPECT_EQ(t60_decay_db(Variant::soundspaces), 30.0);
  EXPECT_EQ(t60_decay_db(Variant::raf), 10.0);
  EXPECT_EQ(stft_params(Variant::raf).n_fft, 1024);
  EXPECT_EQ(stft_params(Variant::raf).win_length, 512);
  EXPECT_EQ(stft_params(Variant::raf).hop_length, 256);
  EXPECT_EQ(stft_params(Variant::soundspaces).n_fft, 512);
  EXPECT_EQ(stft_params(Variant::soundspaces).hop_length, 128);
}

// assets/real/README.md: values with the published semantics, files as they are (44.1 kHz).
struct RealReference {
  const char* file;
  Variant variant;
  int channel;
  double t60, edt, c50;
};

TEST(RealRecordings, MatchTheReferenceValues) {
  const RealReference refs[] = {
      {"rir_clap.wav", Variant::soundspaces, 0, 0.913878, 0.526939, 4.976388},
      {"brir_clap.wav", Variant::soundspaces, 0, 0.553243, 0.655918, 0.659236},
      {"brir_clap.wav", Variant::soundspaces, 1, 0.556735, 0.652245, 0.280130},
      {"rir_clap.wav", Variant::raf, 0, 0.575782, 0.526939, 4.976388},
      {"brir_clap.wav", Variant::raf, 0, 0.522041, 0.655918, 0.659236},
      {"brir_clap.wav", Variant::raf, 1, 0.541497, 0.652245, 0.280130},
  };
  for (const RealReference& r : refs) {
    const io::AudioBuffer rir = io::read_audio(std::string(NERAF_ASSETS_DIR) + "/real/" + r.file);
    const auto a = measure_room_acoustics(rir, r.variant);
    ASSERT_GT(int(a.size()), r.channel);
    const ChannelAcoustics& m = a[r.channel];
    SCOPED_TRACE(std::string(r.file) + " " + to_string(r.variant) + " ch " +
                 std::to_string(r.channel));
    ASSERT_TRUE(m.t60.valid());
    ASSERT_TRUE(m.edt.valid());
    // The table has 6 decimals; one sample at 44.1 kHz moves T60 by >= 4.5e-5 s, EDT by 1.4e-4 s,
    // so agreement to 1e-6 means the same Schroeder indices as the reference.
    EXPECT_NEAR(m.t60.seconds, r.t60, 1e-6);
    EXPECT_NEAR(m.edt.seconds, r.edt, 1e-6);
    EXPECT_NEAR(m.c50_db, r.c50, 1e-6);
  }
}

}  // namespace
}  // namespace neraf::metrics
