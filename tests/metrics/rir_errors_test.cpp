// Per-RIR errors and their aggregation with the reference evaluator's rules.
#include "neraf/metrics/rir_errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "neraf/util/error.h"

namespace neraf::metrics {
namespace {

std::vector<float> decaying_test_noise(double t60, double fs, double seconds, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  const size_t n = static_cast<size_t>(seconds * fs);
  std::vector<float> h(n);
  for (size_t i = 0; i < n; ++i) h[i] = u(rng) * float(std::pow(10.0, -3.0 * (i / fs) / t60));
  return h;
}

TEST(T60Error, MeanRelativeErrorInPercent) {
  bool invalid = true;
  EXPECT_NEAR(t60_error_pct({0.55, 0.45}, {0.5, 0.5}, &invalid), 10.0, 1e-12);
  EXPECT_FALSE(invalid);
  EXPECT_NEAR(t60_error_pct({0.6}, {0.4}, &invalid), 50.0, 1e-12);
  EXPECT_FALSE(invalid);
}

TEST(T60Error, AnyInvalidValueScoresOneHundredPercent) {
  bool invalid = false;
  // One invalid among the 2C values, in the prediction or in the ground truth.
  EXPECT_EQ(t60_error_pct({0.5, -1.0}, {0.5, 0.5}, &invalid), 100.0);
  EXPECT_TRUE(invalid);
  invalid = false;
  EXPECT_EQ(t60_error_pct({0.5, 0.5}, {-1.0, 0.4}, &invalid), 100.0);
  EXPECT_TRUE(invalid);
  // Even when the valid channel alone would be perfect, or when the error would exceed 100 %.
  EXPECT_EQ(t60_error_pct({3.0, -1.0}, {0.5, 0.5}, &invalid), 100.0);
  // The reference's threshold is < −0.5, not < 0.
  EXPECT_NEAR(t60_error_pct({-0.4}, {0.5}, &invalid), 180.0, 1e-12);
  EXPECT_FALSE(invalid);
  EXPECT_THROW(t60_error_pct({0.5}, {0.5, 0.5}, &invalid), Error);
}

TEST(CompareRirs, IdenticalSignalsHaveZeroErrors) {
  const double fs = 22050;
  io::AudioBuffer gt{int(fs),
                     {decaying_test_noise(0.4, fs, 1.0, 1), decaying_test_noise(0.5, fs, 1.0, 2)}};
  for (Variant v : {Variant::soundspaces, Variant::raf}) {
    const RirErrors e = compare_rirs(gt, gt, v);
    EXPECT_EQ(e.t60_error_pct, 0.0);
    EXPECT_EQ(e.c50_error_db, 0.0);
    EXPECT_EQ(e.edt_error_s, 0.0);
    EXPECT_EQ(e.stft_error, 0.0);
    EXPECT_FALSE(e.invalid_t60);
  }
}

TEST(CompareRirs, CombinesPerChannelMeasurements) {
  const double fs = 22050;
  const std::vector<float> g0 = decaying_test_noise(0.4, fs, 1.0, 1),
                           g1 = decaying_test_noise(0.5, fs, 1.0, 2);
  const std::vector<float> p0 = decaying_test_noise(0.3, fs, 1.0, 3),
                           p1 = decaying_test_noise(0.6, fs, 1.0, 4);
  const io::AudioBuffer gt{int(fs), {g0, g1}}, pred{int(fs), {p0, p1}};
  const RirErrors e = compare_rirs(pred, gt, Variant::soundspaces);
  const auto tp0 = measure_t60(p0, fs, 30.0).seconds, tg0 = measure_t60(g0, fs, 30.0).seconds;
  const auto tp1 = measure_t60(p1, fs, 30.0).seconds, tg1 = measure_t60(g1, fs, 30.0).seconds;
  EXPECT_NEAR(e.t60_error_pct, 50.0 * (std::abs(tp0 - tg0) / tg0 + std::abs(tp1 - tg1) / tg1),
              1e-9);
  EXPECT_NEAR(e.edt_error_s,
              0.5 * (std::abs(measure_edt(p0, fs).seconds - measure_edt(g0, fs).seconds) +
                     std::abs(measure_edt(p1, fs).seconds - measure_edt(g1, fs).seconds)),
              1e-12);
  EXPECT_NEAR(e.c50_error_db,
              0.5 * (std::abs(measure_c50(p0, fs) - measure_c50(g0, fs)) +
                     std::abs(measure_c50(p1, fs) - measure_c50(g1, fs))),
              1e-12);
  EXPECT_GT(e.t60_error_pct, 10.0);  // 0.3 vs 0.4 s and 0.6 vs 0.5 s
  // The measured values behind the errors: channel means.
  EXPECT_NEAR(e.t60_pred_s, 0.5 * (tp0 + tp1), 1e-12);
  EXPECT_NEAR(e.t60_gt_s, 0.5 * (tg0 + tg1), 1e-12);
  EXPECT_NEAR(e.c50_pred_db, 0.5 * (measure_c50(p0, fs) + measure_c50(p1, fs)), 1e-12);
  EXPECT_NEAR(e.c50_gt_db, 0.5 * (measure_c50(g0, fs) + measure_c50(g1, fs)), 1e-12);
  EXPECT_FALSE(e.invalid_t60);
  EXPECT_GT(e.stft_error, 0.0);
}

TEST(CompareRirs, SilentPredictionIsInvalidNotACrash) {
  const double fs = 22050;
  const io::AudioBuffer gt{int(fs), {decaying_test_noise(0.4, fs, 1.0, 1)}};
  const io::AudioBuffer pred{int(fs), {std::vector<float>(100, 0.0f)}};  // also shorter: padded
  const RirErrors e = compare_rirs(pred, gt, Variant::raf);
  EXPECT_TRUE(e.invalid_t60);
  EXPECT_EQ(e.t60_error_pct, 100.0);
  EXPECT_TRUE(std::isnan(e.edt_error_s));   // reference: EDT of silence is NaN
  EXPECT_TRUE(std::isnan(e.c50_error_db));  // 10 log10(0/0) = NaN
  EXPECT_TRUE(std::isfinite(e.stft_error));
}

TEST(CompareRirs, PredictionIsZeroPaddedToTheGroundTruthLength) {
  const double fs = 22050;
  const std::vector<float> g = decaying_test_noise(0.3, fs, 0.8, 5);
  std::vector<float> shorter(g.begin(), g.begin() + g.size() - 700);
  std::vector<float> padded = shorter;
  padded.resize(g.size(), 0.0f);
  const io::AudioBuffer gt{int(fs), {g}};
  const RirErrors a = compare_rirs(io::AudioBuffer{int(fs), {shorter}}, gt, Variant::soundspaces);
  const RirErrors b = compare_rirs(io::AudioBuffer{int(fs), {padded}}, gt, Variant::soundspaces);
  EXPECT_EQ(a.t60_error_pct, b.t60_error_pct);
  EXPECT_EQ(a.edt_error_s, b.edt_error_s);
  EXPECT_EQ(a.c50_error_db, b.c50_error_db);
  EXPECT_EQ(a.stft_error, b.stft_error);
  EXPECT_EQ(fit_to_length({1.0f, 2.0f}, 4), (std::vector<float>{1.0f, 2.0f, 0.0f, 0.0f}));
  EXPECT_EQ(fit_to_length({1.0f, 2.0f, 3.0f}, 2), (std::vector<float>{1.0f, 2.0f}));
}

TEST(CompareRirs, MismatchedLayoutsNameBothFiles) {
  const std::vector<float> h = decaying_test_noise(0.3, 22050, 0.5, 1);
  const io::AudioBuffer mono{22050, {h}}, stereo{22050, {h, h}}, other_rate{48000, {h}};
  for (const io::AudioBuffer* p : {&stereo, &other_rate}) {
    try {
      compare_rirs(*p, mono, Variant::soundspaces, "pred.wav", "gt.wav");
      FAIL() << "expected neraf::Error";
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("pred.wav"), std::string::npos) << m;
      EXPECT_NE(m.find("gt.wav"), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  }
  EXPECT_THROW(
      compare_rirs(io::AudioBuffer{22050, {}}, io::AudioBuffer{22050, {}}, Variant::soundspaces),
      Error);
}

TEST(StftError, FramesFollowTheReferenceMaxLen) {
  EXPECT_EQ(stft_error_frames(15360, dsp::StftParams::raf()), 60);  // RAF: 0.32 s at 48 kHz
  EXPECT_EQ(stft_error_frames(101 * 128, dsp::StftParams::soundspaces()), 101);
  EXPECT_EQ(stft_error_frames(10, dsp::StftParams::soundspaces()), 1);
}

TEST(StftError, ZeroForIdenticalSignals) {
  const std::vector<float> h = decaying_test_noise(0.3, 48000, 0.32, 9);
  EXPECT_EQ(stft_error(h, h, dsp::StftParams::raf(), 60), 0.0);
  EXPECT_EQ(stft_error(h, h, dsp::StftParams::soundspaces(), 10), 0.0);
}

TEST(StftError, ConstantSignalsHaveAHandComputedError) {
  // A constant c: every centred, reflect-padded frame is constant, and the DFT of a periodic
  // Hann window of N = n_fft samples is N/2 at bin 0, N/4 in magnitude at bin 1 and 0 elsewhere.
  // So |X| = (c N/2, c N/4, 0, ...) and only bins 0 and 1 differ between two constants.
  const dsp::StftParams p = dsp::StftParams::soundspaces();  // window = n_fft = 512
  const double N = p.n_fft, eps = 1e-3;
  // Small amplitudes keep the float FFT's rounding noise in the zero bins (~1e-8 · c·N) far
  // below the 1e-3 offset of the log.
  const double a = 0.02, b = 0.005;
  const std::vector<float> pred(4096, float(a)), gt(4096, float(b));
  const double bin0 = std::abs(std::log(a * N / 2 + eps) - std::log(b * N / 2 + eps));
  const double bin1 = std::abs(std::log(a * N / 4 + eps) - std::log(b * N / 4 + eps));
  const double expected = (bin0 + bin1) / p.n_freq();  // the 255 other bins contribute ~0
  EXPECT_NEAR(stft_error(pred, gt, p, stft_error_frames(gt.size(), p)), expected, 3e-5);
  EXPECT_NEAR(expected, (std::log(4.0) + std::log(4.0)) / 257.0, 2e-3);  // sanity: ≈ 2 ln 4 / 257
}

TEST(StftError, ScaledSignalMatchesTheFormula) {
  // pred = 4·gt: a power-of-two scale commutes exactly with the float FFT, so |STFT(pred)| =
  // 4·|STFT(gt)| bit for bit and the error is mean |log(4|X| + 1e-3) − log(|X| + 1e-3)|.
  const dsp::StftParams p = dsp::StftParams::raf();
  const std::vector<float> gt = decaying_test_noise(0.2, 48000, 0.32, 11);
  std::vector<float> pred(gt);
  for (float& v : pred) v *= 4.0f;
  const int frames = stft_error_frames(gt.size(), p);
  ASSERT_EQ(frames, 60);
  const dsp::Matrix mag = dsp::magnitude(dsp::stft(gt, p));  // [513, 61]
  ASSERT_EQ(mag.rows, 513);
  ASSERT_EQ(mag.cols, 61);
  double sum = 0.0;
  for (int f = 0; f < mag.rows; ++f) {
    for (int t = 0; t < frames; ++t) {
      sum += std::abs(std::log(4.0 * mag(f, t) + 1e-3) - std::log(double(mag(f, t)) + 1e-3));
    }
  }
  const double expected = sum / (513.0 * frames);
  EXPECT_NEAR(stft_error(pred, gt, p, frames), expected, 1e-5 * expected);
  // Using all 61 frames would give a different number: the truncation is observable.
  double sum61 = sum;
  for (int f = 0; f < mag.rows; ++f) {
    sum61 += std::abs(std::log(4.0 * mag(f, 60) + 1e-3) - std::log(double(mag(f, 60)) + 1e-3));
  }
  EXPECT_NE(sum61 / (513.0 * 61), expected);
}

TEST(StftError, TooShortForTheWindowIsNaN) {
  const std::vector<float> tiny(100, 0.1f);
  EXPECT_TRUE(std::isnan(stft_error(tiny, tiny, dsp::StftParams::raf(), 1)));
}

TEST(Summary, PlainMeanSampleStdAndInvalidFraction) {
  std::vector<RirErrors> all = {{10.0, 1.0, 0.01, 0.5, false},
                                {100.0, 2.0, 0.03, 0.7, true},
                                {40.0, 3.0, 0.02, 0.6, false},
                                {30.0, 6.0, 0.02, 0.2, true}};
  const RirErrorSummary s = summarize(all);
  EXPECT_EQ(s.count, 4u);
  EXPECT_NEAR(s.t60_error_pct.mean, 45.0, 1e-12);
  // Sample std (N − 1): deviations −35, 55, −5, −15 -> (1225 + 3025 + 25 + 225) / 3 = 1500.
  EXPECT_NEAR(s.t60_error_pct.std, std::sqrt(1500.0), 1e-12);
  EXPECT_NEAR(s.c50_error_db.mean, 3.0, 1e-12);
  EXPECT_NEAR(s.edt_error_s.mean, 0.02, 1e-12);
  EXPECT_NEAR(s.stft_error.mean, 0.5, 1e-12);
  EXPECT_NEAR(s.invalid_t60.mean, 0.5, 1e-12);  // a fraction, as the reference's pipeline
  EXPECT_EQ(s.t60_error_pct.non_finite, 0u);

  const MetricStats one = mean_and_std({2.5});
  EXPECT_EQ(one.mean, 2.5);
  EXPECT_TRUE(std::isnan(one.std));  // torch.std of one value
  const MetricStats with_nan = mean_and_std({1.0, std::nan(""), 3.0});
  EXPECT_TRUE(std::isnan(with_nan.mean));  // propagates as the reference's mean does
  EXPECT_EQ(with_nan.non_finite, 1u);
  EXPECT_TRUE(std::isnan(summarize({}).t60_error_pct.mean));
}

TEST(PairedDifference, HandComputedMeanStandardErrorAndWins) {
  // Differences −1, 0, −2, 1 (the NaN pair is left out): mean −0.5; deviations −0.5, 0.5, −1.5,
  // 1.5 → sample variance 5/3; standard error √(5/3) / √4. First better where d < 0: 2 of 4.
  const PairedDifference d =
      paired_difference({1.0, 2.0, 3.0, std::nan(""), 4.0}, {2.0, 2.0, 5.0, 1.0, 3.0});
  EXPECT_EQ(d.count, 4u);
  EXPECT_DOUBLE_EQ(d.mean, -0.5);
  EXPECT_NEAR(d.standard_error, std::sqrt(5.0 / 3.0) / 2.0, 1e-12);
  EXPECT_EQ(d.first_better, 2u);

  const PairedDifference one = paired_difference({1.0}, {3.0});
  EXPECT_DOUBLE_EQ(one.mean, -2.0);
  EXPECT_TRUE(std::isnan(one.standard_error));
  EXPECT_TRUE(std::isnan(paired_difference({}, {}).mean));
  EXPECT_THROW(paired_difference({1.0}, {1.0, 2.0}), Error);
}

}  // namespace
}  // namespace neraf::metrics
