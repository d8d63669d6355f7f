#pragma once
// Small random models for the runtime's tests and tools (header-only; uses only model_file.h).
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "neraf/runtime/model_file.h"

namespace neraf::rt::testing {

struct RandomModelOptions {
  int channels = 2;
  int n_fft = 64, win_length = 64, hop_length = 16;
  int max_len = 12;     // T
  int time_frames = 0;  // the time encoding's frames (0: max_len)
  std::vector<int64_t> trunk = {24, 16};
  bool relative_geometry = false;
  bool calibration = true;
  bool bf16 = false;
  double position_max_freq_exp = 8.0;
  double head_gain = 3.0;  // scales the heads so that tanh saturates somewhere
  int64_t waveform_length = 0;
  uint32_t seed = 1;
};

// PyTorch's default Linear init (uniform ±1/√in) for weights and biases.
inline DenseLayer random_layer(int64_t in, int64_t out, double gain, std::mt19937& gen) {
  DenseLayer l;
  l.in = in;
  l.out = out;
  const double bound = gain / std::sqrt(double(in));
  std::uniform_real_distribution<double> u(-bound, bound);
  l.weight.resize(size_t(in * out));
  l.bias.resize(size_t(out));
  for (float& w : l.weight) w = float(u(gen));
  for (float& b : l.bias) b = float(u(gen));
  return l;
}

inline ModelData random_model(const RandomModelOptions& o = {}) {
  std::mt19937 gen(o.seed);
  ModelData m;
  m.neraf_version = "0.1.0-test";
  m.layout = o.channels == 1 ? 1 : 0;
  m.sample_rate = 22050;
  m.channels = o.channels;
  m.n_fft = o.n_fft;
  m.win_length = o.win_length;
  m.hop_length = o.hop_length;
  m.n_freq = o.n_fft / 2 + 1;
  m.max_len = o.max_len;
  m.time_frames = o.time_frames;
  m.waveform_length = o.waveform_length;
  m.box_min = {-1.0, 0.0, -2.0};
  m.box_max = {3.0, 2.5, 1.5};
  m.relative_geometry = o.relative_geometry;
  m.position_max_freq_exp = o.position_max_freq_exp;
  m.extent_m = {4.0, 2.5, 3.5};
  int64_t in = m.input_dim();
  for (int64_t width : o.trunk) {
    m.trunk.push_back(random_layer(in, width, 1.0, gen));
    in = width;
  }
  for (int c = 0; c < o.channels; ++c)
    m.heads.push_back(random_layer(in, m.n_freq, o.head_gain, gen));
  if (o.calibration) {
    std::uniform_real_distribution<float> g(0.5f, 2.0f);
    m.calibration.resize(size_t(o.channels) * m.n_freq * m.max_len);
    for (float& v : m.calibration) v = g(gen);
  }
  m.bf16_storage = o.bf16;
  m.metadata_json = R"({"frame":"test","note":"random weights"})";
  return m;
}

}  // namespace neraf::rt::testing
