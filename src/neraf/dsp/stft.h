#pragma once
// STFT, inverse STFT and log-magnitude with torchaudio's semantics (the published NeRAF features):
// periodic Hann window of win_length, zero-padded centrally to n_fft; centre=true pads the signal
// by n_fft/2 on both sides with reflection; n_frames = 1 + len/hop (centred); no normalisation.
#include <complex>
#include <cstddef>
#include <optional>
#include <vector>

namespace neraf::dsp {

struct StftParams {
  int n_fft = 512;
  int win_length = 512;
  int hop_length = 128;
  bool center = true;  // reflect-pad n_fft/2 on both sides

  int n_freq() const { return n_fft / 2 + 1; }
  // SoundSpaces recipe (22.05 kHz): n_fft 512, window 512, hop 128.
  static StftParams soundspaces() { return {512, 512, 128, true}; }
  // RAF recipe (48 kHz): n_fft 1024, Hann(512) zero-padded to 1024, hop 256.
  static StftParams raf() { return {1024, 512, 256, true}; }
};

// A [rows, cols] float matrix, row-major. Spectrogram magnitudes are [n_freq, n_frames].
struct Matrix {
  int rows = 0;
  int cols = 0;
  std::vector<float> data;

  Matrix() = default;
  Matrix(int r, int c, float value = 0.0f) : rows(r), cols(c), data(size_t(r) * c, value) {}
  float& operator()(int r, int c) { return data[size_t(r) * cols + c]; }
  float operator()(int r, int c) const { return data[size_t(r) * cols + c]; }
};

// A complex spectrogram [n_freq, n_frames], row-major (frequency outer, as torchaudio's [F, T]).
struct Spectrogram {
  int n_freq = 0;
  int n_frames = 0;
  std::vector<std::complex<float>> data;

  std::complex<float>& operator()(int f, int t) { return data[size_t(f) * n_frames + t]; }
  std::complex<float> operator()(int f, int t) const { return data[size_t(f) * n_frames + t]; }
};

// Number of frames stft() returns for a signal of n samples.
int stft_num_frames(size_t n, const StftParams& p);

Spectrogram stft(const std::vector<float>& signal, const StftParams& p);

// Inverse STFT (overlap-add divided by the summed squared window, as torch.istft). Output length
// hop*(n_frames-1) when `length` is empty (centred), otherwise exactly `length` (zero-padded/cut).
std::vector<float> istft(const Spectrogram& spec, const StftParams& p,
                         std::optional<size_t> length = std::nullopt);

Matrix magnitude(const Spectrogram& spec);  // |X|, [F, T]

// log(|X| + eps), the NeRAF audio feature. eps = 1e-3.
Matrix log_magnitude(const Spectrogram& spec, float eps = 1e-3f);

}  // namespace neraf::dsp
