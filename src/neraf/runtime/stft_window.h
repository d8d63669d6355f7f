#pragma once
// The STFT window of neraf's features (neraf::dsp::StftEngine): a periodic Hann of win_length,
// zero-padded centrally to n_fft (left pad (n_fft − win_length)/2, rounded down), and torch.istft's
// NOLA condition on it. Header-only: the model-file checks and the runtime's Griffin-Lim share it.
#include <cmath>
#include <vector>

namespace neraf::rt {

// [n_fft] floats, exactly as StftEngine computes them (in double, rounded once).
inline std::vector<float> padded_hann_window(int n_fft, int win_length) {
  std::vector<float> w(n_fft, 0.0f);
  const int begin = (n_fft - win_length) / 2;
  for (int k = 0; k < win_length; ++k)
    w[begin + k] = static_cast<float>(0.5 - 0.5 * std::cos(2.0 * M_PI * k / win_length));
  return w;
}

// Whether windows at this hop cover every sample (otherwise the inverse STFT is undefined).
inline bool satisfies_nola(const std::vector<float>& window, int hop) {
  const int n = static_cast<int>(window.size());
  for (int s = 0; s < hop; ++s) {
    double sum = 0.0;
    for (int j = s; j < n; j += hop) sum += double(window[j]) * window[j];
    if (!(sum > 1e-11)) return false;
  }
  return true;
}

}  // namespace neraf::rt
