// The runtime's Griffin-Lim against neraf::dsp::griffin_lim (the implementation the training and
// evaluation code use): the same magnitudes and seed must give the same waveform.
#include "neraf/runtime/griffin_lim.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

#include "neraf/dsp/griffin_lim.h"
#include "neraf/neraf_rt.h"
#include "random_model.h"

namespace fs = std::filesystem;

namespace {

// Relative difference max|a − b| / max|b|.
double relative_diff(const std::vector<float>& a, const std::vector<float>& b) {
  EXPECT_EQ(a.size(), b.size());
  double d = 0, m = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    d = std::max(d, std::fabs(double(a[i]) - b[i]));
    m = std::max(m, std::fabs(double(b[i])));
  }
  return m > 0 ? d / m : d;
}

// RIR-like magnitudes [F, T]: a decaying envelope times log-normal noise.
std::vector<float> test_magnitudes(int F, int T, uint32_t seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> g;
  std::vector<float> m(size_t(F) * T);
  for (int f = 0; f < F; ++f)
    for (int t = 0; t < T; ++t)
      m[size_t(f) * T + t] = float(std::exp(-0.15 * t - 0.002 * f + 0.5 * g(gen)));
  return m;
}

void expect_same_as_dsp(int n_fft, int win, int hop, int T, int channels, int n_iter,
                        uint64_t seed) {
  const neraf::rt::GriffinLim gl(n_fft, win, hop, T);
  const int F = gl.n_freq();
  std::vector<std::vector<float>> mags;
  std::vector<neraf::dsp::Matrix> mats;
  for (int c = 0; c < channels; ++c) {
    mags.push_back(test_magnitudes(F, T, 10 + c));
    neraf::dsp::Matrix x(F, T);
    x.data = mags.back();
    mats.push_back(x);
  }
  neraf::dsp::GriffinLimOptions o;
  o.n_iter = n_iter;
  o.seed = seed;
  const neraf::dsp::StftParams p{n_fft, win, hop, true};
  const std::vector<std::vector<float>> want = neraf::dsp::griffin_lim(mats, p, o);

  std::vector<float> phases(size_t(channels) * T * gl.phase_stride());
  gl.random_phases(seed, channels, phases.data());
  neraf::rt::GriffinLimBuffers b = gl.make_buffers();
  for (int c = 0; c < channels; ++c) {
    std::vector<float> got(size_t(gl.length()));
    gl.run(mags[c].data(), phases.data() + size_t(c) * T * gl.phase_stride(), n_iter, b,
           got.data(), gl.length());
    // Measured: bit-identical (same plans, same arithmetic); the bound leaves room for compilers.
    EXPECT_LT(relative_diff(got, want[c]), 1e-6)
        << "n_fft " << n_fft << " win " << win << " hop " << hop << " channel " << c;
  }
}

}  // namespace

TEST(RuntimeGriffinLim, EqualsDspSoundSpaces) { expect_same_as_dsp(512, 512, 128, 30, 2, 32, 0); }

TEST(RuntimeGriffinLim, EqualsDspRafWindowShorterThanFft) {
  expect_same_as_dsp(1024, 512, 256, 12, 1, 32, 42);
}

TEST(RuntimeGriffinLim, EqualsDspOddSizesAndFewIterations) {
  expect_same_as_dsp(60, 45, 15, 7, 3, 3, 5);
  expect_same_as_dsp(64, 64, 16, 2, 1, 0, 1);
}

// Through the C API: neraf_query_rir's waveform is Griffin-Lim of neraf_query_log_stft's
// magnitudes clip(e^x − 1e-3, 0, 1e4), cut or zero-padded to rir_length.
TEST(RuntimeGriffinLim, QueryRirIsGriffinLimOfTheLogStft) {
  for (int64_t waveform_length : {int64_t(0), int64_t(100), int64_t(400)}) {
    neraf::rt::testing::RandomModelOptions o;
    o.waveform_length = waveform_length;  // default hop·(T−1) = 176
    std::string t = (fs::temp_directory_path() / "neraf_rt_gl_XXXXXX").string();
    const fs::path dir = ::mkdtemp(t.data());
    const std::string path = (dir / "m.nrf").string();
    neraf::rt::write_model_file(path, neraf::rt::testing::random_model(o));
    neraf_model* model = nullptr;
    ASSERT_EQ(neraf_model_load(path.c_str(), &model), NERAF_OK) << neraf_last_error();
    neraf_model_info info;
    neraf_model_get_info(model, &info);
    EXPECT_EQ(info.rir_length, waveform_length ? waveform_length : 16 * 11);
    neraf_workspace* ws = nullptr;
    ASSERT_EQ(neraf_workspace_create(model, &ws), NERAF_OK);
    ASSERT_EQ(neraf_workspace_set_griffin_lim(ws, 20, 9), NERAF_OK);

    const neraf_pose pose = {{0.5, 1.2, -0.5}, {2.0, 1.5, 1.0}, 45.0};
    const int C = info.channels, F = info.n_freq, T = info.n_frames;
    std::vector<float> log(size_t(C) * F * T), rir(size_t(C) * info.rir_length);
    ASSERT_EQ(neraf_query_log_stft(model, ws, &pose, 0, log.data(), log.size()), NERAF_OK);
    ASSERT_EQ(neraf_query_rir(model, ws, &pose, 0, rir.data(), rir.size()), NERAF_OK);
    std::vector<neraf::dsp::Matrix> mats;
    for (int c = 0; c < C; ++c) {
      neraf::dsp::Matrix x(F, T);
      for (size_t i = 0; i < x.data.size(); ++i)
        x.data[i] = std::clamp(std::exp(log[size_t(c) * F * T + i]) - 1e-3f, 0.0f, 1e4f);
      mats.push_back(x);
    }
    neraf::dsp::GriffinLimOptions go;
    go.n_iter = 20;
    go.seed = 9;
    const neraf::dsp::StftParams p{info.n_fft, info.win_length, info.hop_length, true};
    std::vector<std::vector<float>> want = neraf::dsp::griffin_lim(mats, p, go);
    for (int c = 0; c < C; ++c) {
      want[c].resize(size_t(info.rir_length), 0.0f);  // as train::griffin_lim_channels
      const std::vector<float> got(rir.begin() + size_t(c) * info.rir_length,
                                   rir.begin() + size_t(c + 1) * info.rir_length);
      EXPECT_LT(relative_diff(got, want[c]), 1e-4) << "waveform_length " << waveform_length;
    }
    neraf_workspace_free(ws);
    neraf_model_free(model);
    fs::remove_all(dir);
  }
}
