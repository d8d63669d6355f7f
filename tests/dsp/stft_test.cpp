#include "neraf/dsp/stft.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <complex>
#include <random>

#include "neraf/util/error.h"

using neraf::dsp::Spectrogram;
using neraf::dsp::StftParams;

namespace {

std::vector<float> random_signal(size_t n, uint32_t seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<float> g(0.0f, 0.3f);
  std::vector<float> x(n);
  for (float& v : x) v = g(gen);
  return x;
}

// The definition, written out independently of the implementation, in double precision:
// periodic Hann(win) placed at (n_fft − win)/2 in an n_fft frame; signal reflect-padded by n_fft/2
// (x[−k] = x[k], x[L−1+k] = x[L−1−k]); frame t starts at t·hop; X[f,t] = Σ_j
// w[j]·p[t·hop+j]·e^{−2πi fj/n}.
std::vector<std::vector<std::complex<double>>> reference_stft(const std::vector<float>& x,
                                                              const StftParams& p) {
  const int n = p.n_fft, win = p.win_length, hop = p.hop_length;
  const int64_t len = static_cast<int64_t>(x.size());
  std::vector<double> w(n, 0.0);
  for (int k = 0; k < win; ++k) w[(n - win) / 2 + k] = 0.5 - 0.5 * std::cos(2.0 * M_PI * k / win);
  const int pad = n / 2;
  std::vector<double> padded(len + 2 * pad);
  for (int64_t i = 0; i < len; ++i) padded[i + pad] = x[i];
  for (int k = 1; k <= pad; ++k) {
    padded[pad - k] = x[k];
    padded[pad + len - 1 + k] = x[len - 1 - k];
  }
  const int frames = 1 + static_cast<int>(len / hop);
  std::vector<std::vector<std::complex<double>>> X(n / 2 + 1,
                                                   std::vector<std::complex<double>>(frames));
  for (int t = 0; t < frames; ++t) {
    for (int f = 0; f <= n / 2; ++f) {
      std::complex<double> acc = 0.0;
      for (int j = 0; j < n; ++j) {
        if (w[j] == 0.0) continue;
        const double ph = -2.0 * M_PI * double(f) * j / n;
        acc += w[j] * padded[t * hop + j] * std::complex<double>(std::cos(ph), std::sin(ph));
      }
      X[f][t] = acc;
    }
  }
  return X;
}

void expect_matches_reference(const std::vector<float>& x, const StftParams& p) {
  const Spectrogram S = neraf::dsp::stft(x, p);
  const auto R = reference_stft(x, p);
  ASSERT_EQ(S.n_freq, p.n_fft / 2 + 1);
  ASSERT_EQ(S.n_frames, static_cast<int>(R[0].size()));
  double max_ref = 0.0, max_err = 0.0;
  for (int f = 0; f < S.n_freq; ++f) {
    for (int t = 0; t < S.n_frames; ++t) {
      max_ref = std::max(max_ref, std::abs(R[f][t]));
      max_err = std::max(max_err, std::abs(std::complex<double>(S(f, t)) - R[f][t]));
    }
  }
  EXPECT_LT(max_err, 2e-5 * max_ref) << "max |ref| " << max_ref;
}

}  // namespace

TEST(Stft, FrameCountRule) {
  // 1 + len/hop, centred (torch.stft(center=True)).
  EXPECT_EQ(neraf::dsp::stft_num_frames(15360, StftParams::raf()), 61);
  EXPECT_EQ(neraf::dsp::stft_num_frames(22050, StftParams::soundspaces()), 173);
  EXPECT_EQ(neraf::dsp::stft_num_frames(255, StftParams::raf()), 1);
  EXPECT_EQ(neraf::dsp::stft_num_frames(256, StftParams::raf()), 2);
  StftParams nc = StftParams::soundspaces();
  nc.center = false;
  EXPECT_EQ(neraf::dsp::stft_num_frames(511, nc), 0);
  EXPECT_EQ(neraf::dsp::stft_num_frames(512, nc), 1);
  EXPECT_EQ(neraf::dsp::stft_num_frames(512 + 127, nc), 1);
  EXPECT_EQ(neraf::dsp::stft_num_frames(512 + 128, nc), 2);
  const auto S = neraf::dsp::stft(random_signal(15360, 1), StftParams::raf());
  EXPECT_EQ(S.n_freq, 513);
  EXPECT_EQ(S.n_frames, 61);
}

TEST(Stft, MatchesDirectDftSoundSpaces) {
  // A length that is not a multiple of hop, so the last frame reaches into the reflected tail.
  expect_matches_reference(random_signal(3000, 2), StftParams::soundspaces());
}

TEST(Stft, MatchesDirectDftRaf) {
  // Hann(512) zero-padded to 1024; 0.1 s at 48 kHz.
  expect_matches_reference(random_signal(4800, 3), StftParams::raf());
}

TEST(Stft, WindowIsZeroPaddedCentrally) {
  // An impulse at sample 0 (frame 0's centre, after reflect padding nothing else is nonzero in
  // frame 0): X[f, 0] = w[n/2]·e^{−2πi f (n/2)/n} = (−1)^f · w_hann[win/2] = (−1)^f.
  std::vector<float> x(4096, 0.0f);
  x[0] = 1.0f;
  const auto S = neraf::dsp::stft(x, StftParams::raf());
  for (int f = 0; f < 513; f += 37) {
    EXPECT_NEAR(S(f, 0).real(), (f % 2 ? -1.0 : 1.0), 1e-5) << f;
    EXPECT_NEAR(S(f, 0).imag(), 0.0, 1e-5) << f;
  }
  // An impulse 200 samples after frame 1's centre lies inside the 512-sample window
  // (support ±256): its weight is w_hann[256 + 200]. 300 samples after lies outside: 0.
  for (int offset : {200, 300}) {
    std::vector<float> y(4096, 0.0f);
    y[256 + offset] = 1.0f;
    const auto T = neraf::dsp::stft(y, StftParams::raf());
    const double expected =
        offset < 256 ? 0.5 - 0.5 * std::cos(2 * M_PI * (256 + offset) / 512) : 0.0;
    EXPECT_NEAR(std::abs(T(0, 1)), expected, 1e-6) << offset;
  }
}

TEST(Stft, ReflectPaddingDoesNotRepeatTheEdge) {
  // x = [0, 1, 2, ...]: frame 0 sees reflect(x) = [..., 2, 1, 0, 1, 2, ...], which is even about
  // sample 0, so with the symmetric window the spectrum of frame 0 is real·(−1)^f: imag ≈ 0. An
  // edge-repeating ("symmetric") pad would break that symmetry.
  std::vector<float> x(2048);
  for (size_t i = 0; i < x.size(); ++i) x[i] = 0.001f * float(i);
  const auto S = neraf::dsp::stft(x, StftParams::soundspaces());
  double max_imag = 0.0, max_abs = 0.0;
  for (int f = 0; f < S.n_freq; ++f) {
    max_imag = std::max(max_imag, double(std::abs(S(f, 0).imag())));
    max_abs = std::max(max_abs, double(std::abs(S(f, 0))));
  }
  EXPECT_LT(max_imag, 1e-5 * max_abs);
  expect_matches_reference(x, StftParams::soundspaces());
}

TEST(Stft, RoundTripReconstructsBothParameterSets) {
  for (const StftParams& p : {StftParams::soundspaces(), StftParams::raf()}) {
    for (size_t len : {size_t(15360), size_t(10001)}) {
      const auto x = random_signal(len, 4);
      const auto S = neraf::dsp::stft(x, p);
      const auto y = neraf::dsp::istft(S, p, len);
      ASSERT_EQ(y.size(), len);
      double err = 0.0;
      for (size_t i = 0; i < len; ++i) err = std::max(err, double(std::abs(y[i] - x[i])));
      EXPECT_LT(err, 1e-5) << "n_fft " << p.n_fft << " len " << len;
    }
  }
}

TEST(Stft, IstftDefaultLengthAndZeroPadding) {
  const StftParams p = StftParams::raf();
  const auto x = random_signal(15360, 5);
  const auto S = neraf::dsp::stft(x, p);  // 61 frames
  const auto y = neraf::dsp::istft(S, p);
  EXPECT_EQ(y.size(), size_t(256 * 60));
  for (size_t i = 0; i < y.size(); ++i) ASSERT_NEAR(y[i], x[i], 1e-5) << i;
  // Longer than the frames reach: torch.istft zero-pads.
  const auto z = neraf::dsp::istft(S, p, 20000);
  ASSERT_EQ(z.size(), 20000u);
  for (size_t i = 0; i < 15360; ++i) ASSERT_NEAR(z[i], x[i], 1e-5) << i;
  for (size_t i = 15360 + 512; i < z.size(); ++i) ASSERT_EQ(z[i], 0.0f) << i;
}

TEST(Stft, IstftMatchesDirectOverlapAdd) {
  // A spectrogram that is not the STFT of anything: istft must still follow torch.istft's
  // definition, y = Σ_t w·irfft(X_t) shifted by t·hop, divided by Σ_t w² shifted, centre trimmed.
  // (irfft ignores the imaginary parts of the DC and Nyquist bins.)
  const StftParams p = StftParams::soundspaces();
  const int n = p.n_fft, hop = p.hop_length, F = n / 2 + 1, T = 9;
  std::mt19937 gen(6);
  std::normal_distribution<float> g;
  Spectrogram S;
  S.n_freq = F;
  S.n_frames = T;
  S.data.resize(size_t(F) * T);
  for (auto& v : S.data) v = {g(gen), g(gen)};
  const auto y = neraf::dsp::istft(S, p);
  ASSERT_EQ(y.size(), size_t(hop * (T - 1)));

  std::vector<double> w(n);
  for (int k = 0; k < n; ++k) w[k] = 0.5 - 0.5 * std::cos(2 * M_PI * k / n);
  const int total = n + hop * (T - 1);
  std::vector<double> ola(total, 0.0), env(total, 0.0);
  for (int t = 0; t < T; ++t) {
    for (int j = 0; j < n; ++j) {
      double v = S(0, t).real() + S(F - 1, t).real() * ((j % 2) ? -1.0 : 1.0);
      for (int f = 1; f < F - 1; ++f) {
        const double ph = 2 * M_PI * double(f) * j / n;
        v += 2.0 * (S(f, t).real() * std::cos(ph) - S(f, t).imag() * std::sin(ph));
      }
      ola[t * hop + j] += w[j] * v / n;
      env[t * hop + j] += w[j] * w[j];
    }
  }
  double max_err = 0.0, max_ref = 0.0;
  for (size_t i = 0; i < y.size(); ++i) {
    const double ref = ola[i + n / 2] / env[i + n / 2];
    max_ref = std::max(max_ref, std::abs(ref));
    max_err = std::max(max_err, std::abs(ref - y[i]));
  }
  EXPECT_LT(max_err, 1e-5 * max_ref);
}

TEST(Stft, LongSignalsGiveTheSameNumbersWithAnyThreadCount) {
  // Long enough for the parallel path (≥ 2^18 samples of frame work).
  const auto x = random_signal(48000 * 6, 8);
  for (const StftParams& p : {StftParams::soundspaces(), StftParams::raf()}) {
    const auto S = neraf::dsp::stft(x, p);
    const auto y = neraf::dsp::istft(S, p, x.size());
    const int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    const auto S1 = neraf::dsp::stft(x, p);
    const auto y1 = neraf::dsp::istft(S, p, x.size());
    omp_set_num_threads(threads);
    EXPECT_EQ(S.data, S1.data);
    EXPECT_EQ(y, y1);
    double err = 0.0;
    for (size_t i = 0; i < x.size(); ++i) err = std::max(err, double(std::abs(y[i] - x[i])));
    EXPECT_LT(err, 1e-5);
  }
}

TEST(Stft, LogMagnitude) {
  Spectrogram S;
  S.n_freq = 1;
  S.n_frames = 3;
  S.data = {{3.0f, 4.0f}, {0.0f, 0.0f}, {-1.0f, 0.0f}};
  const auto m = neraf::dsp::magnitude(S);
  EXPECT_FLOAT_EQ(m(0, 0), 5.0f);
  EXPECT_FLOAT_EQ(m(0, 2), 1.0f);
  const auto l = neraf::dsp::log_magnitude(S);
  EXPECT_FLOAT_EQ(l(0, 0), std::log(5.001f));
  EXPECT_FLOAT_EQ(l(0, 1), std::log(1e-3f));
}

TEST(Stft, RejectsBadParameters) {
  const auto x = random_signal(1000, 7);
  EXPECT_THROW(neraf::dsp::stft(x, {512, 1024, 128, true}), neraf::Error);  // window > n_fft
  EXPECT_THROW(neraf::dsp::stft(x, {512, 512, 0, true}), neraf::Error);     // hop 0
  StftParams nc{2048, 2048, 512, false};
  EXPECT_THROW(neraf::dsp::stft(x, nc), neraf::Error);  // shorter than n_fft, not centred
  // Hop equal to the Hann length leaves zeros in the envelope: no inverse.
  const auto S = neraf::dsp::stft(x, {512, 512, 512, true});
  EXPECT_THROW(neraf::dsp::istft(S, {512, 512, 512, true}), neraf::Error);
  EXPECT_THROW(neraf::dsp::istft(S, StftParams::raf()), neraf::Error);  // wrong bin count
}

TEST(Stft, ShortSignalsUseRepeatedReflection) {
  // torch refuses pads longer than the signal; here they reflect repeatedly (numpy's "reflect").
  const std::vector<float> x = {1.0f, 2.0f, 3.0f};
  const auto S = neraf::dsp::stft(x, StftParams::soundspaces());
  EXPECT_EQ(S.n_frames, 1);
  // Padded signal is periodic 1,2,3,2,1,2,3,...: the DC of frame 0 is the windowed sum.
  std::vector<double> w(512);
  double dc = 0.0;
  for (int j = 0; j < 512; ++j) {
    w[j] = 0.5 - 0.5 * std::cos(2 * M_PI * j / 512);
    const int64_t k = std::abs(j - 256) % 4;
    dc += w[j] * (k == 3 ? 2.0 : 1.0 + k);
  }
  EXPECT_NEAR(S(0, 0).real(), dc, 1e-3);
  EXPECT_EQ(neraf::dsp::stft({}, StftParams::soundspaces()).n_frames, 1);
}
