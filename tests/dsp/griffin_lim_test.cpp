#include "neraf/dsp/griffin_lim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "neraf/util/error.h"

using neraf::dsp::GriffinLimOptions;
using neraf::dsp::Matrix;
using neraf::dsp::StftParams;

namespace {

// A RIR-like test signal: a few decaying tones plus exponentially decaying noise.
std::vector<float> test_signal(size_t n, double fs, uint32_t seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> g;
  std::vector<float> x(n);
  for (size_t i = 0; i < n; ++i) {
    const double t = i / fs;
    const double env = std::exp(-t / 0.3);
    x[i] = static_cast<float>(env * (0.3 * std::sin(2 * M_PI * 440 * t) +
                                     0.2 * std::sin(2 * M_PI * 1870 * t) + 0.1 * g(gen)));
  }
  return x;
}

// ‖ |STFT(y)| − S ‖_F / ‖S‖_F.
double spectral_convergence(const std::vector<float>& y, const Matrix& target,
                            const StftParams& p) {
  const Matrix m = neraf::dsp::magnitude(neraf::dsp::stft(y, p));
  EXPECT_EQ(m.rows, target.rows);
  EXPECT_EQ(m.cols, target.cols);
  double num = 0.0, den = 0.0;
  for (size_t i = 0; i < m.data.size(); ++i) {
    num += std::pow(double(m.data[i]) - target.data[i], 2);
    den += std::pow(double(target.data[i]), 2);
  }
  return std::sqrt(num / den);
}

// Straightforward Griffin-Lim from the public stft/istft, as torchaudio writes it, with the same
// random initial phases (torch's CPU recipe: mt19937, (x & 0xFFFFFF)·2^-24, [freq][frame][re, im]).
std::vector<float> reference_griffin_lim(const Matrix& S, const StftParams& p, int n_iter,
                                         float momentum, uint64_t seed) {
  const double m = double(momentum) / (1.0 + momentum);
  std::mt19937 gen(static_cast<uint32_t>(seed));
  auto u = [&] { return float(gen() & 0xFFFFFFu) / 16777216.0f; };
  neraf::dsp::Spectrogram angles;
  angles.n_freq = S.rows;
  angles.n_frames = S.cols;
  angles.data.resize(S.data.size());
  for (auto& a : angles.data) {
    const float re = u();
    a = {re, u()};
  }
  auto times_mag = [&](const neraf::dsp::Spectrogram& a) {
    neraf::dsp::Spectrogram s = a;
    for (size_t i = 0; i < s.data.size(); ++i) s.data[i] *= S.data[i];
    return s;
  };
  std::vector<std::complex<float>> prev(S.data.size(), 0.0f);
  for (int it = 0; it < n_iter; ++it) {
    const auto x = neraf::dsp::istft(times_mag(angles), p);
    const auto r = neraf::dsp::stft(x, p);
    for (size_t i = 0; i < r.data.size(); ++i) {
      const std::complex<float> a = r.data[i] - float(m) * prev[i];
      angles.data[i] = a / (std::abs(a) + 1e-16f);
      prev[i] = r.data[i];
    }
  }
  return neraf::dsp::istft(times_mag(angles), p);
}

double max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  double d = 0.0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    d = std::max(d, double(std::abs(a[i] - b[i])));
  return d;
}

double max_abs(const std::vector<float>& a) {
  double d = 0.0;
  for (float v : a) d = std::max(d, double(std::abs(v)));
  return d;
}

}  // namespace

TEST(GriffinLim, ConvergesOnAKnownMagnitudeRaf) {
  const StftParams p = StftParams::raf();
  const auto x = test_signal(15360, 48000, 1);
  const Matrix S = neraf::dsp::magnitude(neraf::dsp::stft(x, p));  // [513, 61]
  std::vector<double> sc;
  for (int iters : {0, 2, 8, 32, 100}) {
    GriffinLimOptions o;
    o.n_iter = iters;
    o.seed = 3;
    const auto y = neraf::dsp::griffin_lim(S, p, o);
    EXPECT_EQ(y.size(), size_t(256 * 60));
    sc.push_back(spectral_convergence(y, S, p));
  }
  for (size_t i = 1; i < sc.size(); ++i) EXPECT_LT(sc[i], sc[i - 1]) << "step " << i;
  EXPECT_GT(sc[0], 0.5);   // random phases are far off
  EXPECT_LT(sc[3], 0.12);  // 32 iterations (the NeRAF setting)
  EXPECT_LT(sc[4], 0.07);
}

TEST(GriffinLim, ConvergesOnAKnownMagnitudeSoundSpaces) {
  const StftParams p = StftParams::soundspaces();
  const auto x = test_signal(12800, 22050, 2);
  const Matrix S = neraf::dsp::magnitude(neraf::dsp::stft(x, p));  // [257, 101]
  GriffinLimOptions o;
  o.n_iter = 0;
  const double sc0 = spectral_convergence(neraf::dsp::griffin_lim(S, p, o), S, p);
  o.n_iter = 32;
  const double sc32 = spectral_convergence(neraf::dsp::griffin_lim(S, p, o), S, p);
  EXPECT_GT(sc0, 0.5);
  EXPECT_LT(sc32, 0.12);
}

TEST(GriffinLim, MatchesTheStraightforwardAlgorithm) {
  // Same arithmetic through the public stft/istft: differences are float rounding only.
  const StftParams p = StftParams::raf();
  const Matrix S = neraf::dsp::magnitude(neraf::dsp::stft(test_signal(7680, 48000, 4), p));
  for (int iters : {0, 1, 4}) {
    GriffinLimOptions o;
    o.n_iter = iters;
    o.seed = 11;
    const auto y = neraf::dsp::griffin_lim(S, p, o);
    const auto r = reference_griffin_lim(S, p, iters, o.momentum, o.seed);
    EXPECT_LT(max_abs_diff(y, r), 1e-4 * max_abs(r)) << iters << " iterations";
  }
}

TEST(GriffinLim, DeterministicPerSeedAndThreadCount) {
  const StftParams p = StftParams::raf();
  const Matrix S = neraf::dsp::magnitude(neraf::dsp::stft(test_signal(15360, 48000, 5), p));
  GriffinLimOptions o;
  o.seed = 42;
  const auto a = neraf::dsp::griffin_lim(S, p, o);
  const auto b = neraf::dsp::griffin_lim(S, p, o);
  EXPECT_EQ(a, b);
  for (int threads :
       {1, 2, 3}) {  // serial, and frames shared by a team (forced, whatever the load)
    o.threads = threads;
    EXPECT_EQ(a, neraf::dsp::griffin_lim(S, p, o)) << threads << " threads";
  }
  o.threads = 0;
  o.seed = 43;
  const auto d = neraf::dsp::griffin_lim(S, p, o);
  EXPECT_GT(max_abs_diff(a, d), 1e-3 * max_abs(a)) << "different seeds give different phases";
}

TEST(GriffinLim, OnesInitIsDeterministicWithoutSeed) {
  const StftParams p = StftParams::soundspaces();
  const Matrix S = neraf::dsp::magnitude(neraf::dsp::stft(test_signal(5000, 22050, 6), p));
  GriffinLimOptions o;
  o.rand_init = false;
  o.seed = 1;
  const auto a = neraf::dsp::griffin_lim(S, p, o);
  o.seed = 2;
  EXPECT_EQ(a, neraf::dsp::griffin_lim(S, p, o));
}

TEST(GriffinLim, MultichannelMatchesPerChannelRandomStream) {
  const StftParams p = StftParams::soundspaces();
  const Matrix L = neraf::dsp::magnitude(neraf::dsp::stft(test_signal(12800, 22050, 7), p));
  const Matrix R = neraf::dsp::magnitude(neraf::dsp::stft(test_signal(12800, 22050, 8), p));
  GriffinLimOptions o;
  o.seed = 5;
  const auto both = neraf::dsp::griffin_lim(std::vector<Matrix>{L, R}, p, o);
  ASSERT_EQ(both.size(), 2u);
  // Channel 0 consumes the stream first, exactly like a single-channel call.
  EXPECT_EQ(both[0], neraf::dsp::griffin_lim(L, p, o));
  // Channel 1's phases continue the stream: not the same as starting it afresh.
  const auto r_alone = neraf::dsp::griffin_lim(R, p, o);
  EXPECT_GT(max_abs_diff(both[1], r_alone), 1e-4 * max_abs(r_alone));
  EXPECT_LT(spectral_convergence(both[1], R, p), 0.12);
  // Same result serially, with a channel per thread (2) and with frames shared by a team (3).
  for (int threads : {1, 2, 3}) {
    o.threads = threads;
    EXPECT_EQ(both, neraf::dsp::griffin_lim(std::vector<Matrix>{L, R}, p, o)) << threads;
  }
}

TEST(GriffinLim, LengthOption) {
  const StftParams p = StftParams::raf();
  const Matrix S =
      neraf::dsp::magnitude(neraf::dsp::stft(test_signal(15360, 48000, 9), p));  // 61 frames
  GriffinLimOptions o;
  o.length = 15360 + 100;  // 1 + len/hop == 61: used inside the iterations, as torch does
  EXPECT_EQ(neraf::dsp::griffin_lim(S, p, o).size(), 15460u);
  o.length = 20000;  // torch would fail; here the result is zero-padded
  const auto y = neraf::dsp::griffin_lim(S, p, o);
  ASSERT_EQ(y.size(), 20000u);
  o.length.reset();
  const auto z = neraf::dsp::griffin_lim(S, p, o);
  for (size_t i = 0; i < z.size(); ++i) ASSERT_EQ(y[i], z[i]);
  for (size_t i = z.size(); i < y.size(); ++i) ASSERT_EQ(y[i], 0.0f);
}

TEST(GriffinLim, RejectsBadInput) {
  const StftParams p = StftParams::raf();
  Matrix wrong(257, 10, 1.0f);
  EXPECT_THROW(neraf::dsp::griffin_lim(wrong, p), neraf::Error);
  Matrix nan(513, 10, 1.0f);
  nan(3, 4) = std::nanf("");
  EXPECT_THROW(neraf::dsp::griffin_lim(nan, p), neraf::Error);
  GriffinLimOptions o;
  o.threads = -1;
  EXPECT_THROW(neraf::dsp::griffin_lim(Matrix(513, 10, 1.0f), p, o), neraf::Error);
  o.threads = 0;
  o.momentum = 1.0f;
  EXPECT_THROW(neraf::dsp::griffin_lim(Matrix(513, 10, 1.0f), p, o), neraf::Error);
  EXPECT_THROW(neraf::dsp::griffin_lim(std::vector<Matrix>{Matrix(513, 10), Matrix(513, 11)}, p),
               neraf::Error);
}
