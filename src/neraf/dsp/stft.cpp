#include "neraf/dsp/stft.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "neraf/dsp/stft_engine.h"
#include "neraf/util/error.h"

namespace neraf::dsp {
namespace detail {
namespace {

int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Frames are transformed in parallel only for long signals (≥ 256 frames of 1024): a typical RIR's
// STFT takes ~0.1 ms, less than the cost of waking threads on a busy machine; callers with many
// RIRs parallelise over RIRs instead. Frames are handed out in small dynamic chunks so a thread
// descheduled by other processes delays only its chunk; results do not depend on who computes
// what.
constexpr int64_t kParallelSamples = int64_t(1) << 18;

}  // namespace

bool cores_busy() {
  double load = 0.0;
  return getloadavg(&load, 1) == 1 && load > omp_get_num_procs() + 0.5;
}

void validate(const StftParams& p) {
  const std::string where = "STFT parameters (n_fft " + std::to_string(p.n_fft) + ", win_length " +
                            std::to_string(p.win_length) + ", hop_length " +
                            std::to_string(p.hop_length) + ")";
  require(p.n_fft >= 2, where + ": n_fft must be at least 2");
  require(p.win_length >= 1 && p.win_length <= p.n_fft,
          where + ": win_length must be between 1 and n_fft");
  require(p.hop_length >= 1, where + ": hop_length must be positive");
}

StftEngine::StftEngine(const StftParams& p) {
  validate(p);
  n_fft_ = p.n_fft;
  n_freq_ = p.n_freq();
  hop_ = p.hop_length;
  center_ = p.center;
  spec_stride_ = aligned_stride(2 * size_t(n_freq_));
  frame_stride_ = aligned_stride(size_t(n_fft_));
  // Periodic Hann of win_length (torch.hann_window(periodic=True)), zero-padded centrally to n_fft
  // with the left pad (n_fft − win_length)/2 rounded down, as torch.stft pads a short window.
  const int win = p.win_length;
  sb_ = (n_fft_ - win) / 2;
  se_ = sb_ + win;
  window_.assign(n_fft_, 0.0f);
  for (int k = 0; k < win; ++k) {
    window_[sb_ + k] = static_cast<float>(0.5 - 0.5 * std::cos(2.0 * M_PI * k / win));
  }
  // Out-of-place transforms: FFTW_ESTIMATE buffers (copies) in-place real transforms of these
  // sizes, measured ~20 % slower.
  r2c_ = fft_plan(FftKind::r2c, n_fft_);
  c2r_ = fft_plan(FftKind::c2r, n_fft_);
}

int64_t StftEngine::default_length(int n_frames) const {
  const int64_t expected = n_fft_ + int64_t(hop_) * (n_frames - 1);
  return center_ ? expected - 2 * (n_fft_ / 2) : expected;
}

void StftEngine::forward_frame(const float* support, float* scratch, float* spec) const {
  const float* w = window_.data() + sb_;
  float* dst = scratch + sb_;
  for (int j = 0; j < se_ - sb_; ++j) dst[j] = support[j] * w[j];
  fftwf_execute_dft_r2c(r2c_, scratch, reinterpret_cast<fftwf_complex*>(spec));
}

void StftEngine::inverse_frame(float* spec, float* frame) const {
  fftwf_execute_dft_c2r(c2r_, reinterpret_cast<fftwf_complex*>(spec), frame);
}

std::vector<float> StftEngine::inverse_envelope(int n_frames, int64_t c_begin,
                                                int64_t c_end) const {
  const int64_t n = std::max<int64_t>(0, c_end - c_begin);
  std::vector<double> env(n, 0.0);
  for (int t = 0; t < n_frames; ++t) {
    const int64_t base = int64_t(t) * hop_;
    const int64_t a = std::max(c_begin, base + sb_), b = std::min(c_end, base + se_);
    for (int64_t c = a; c < b; ++c) {
      const double w = window_[c - base];
      env[c - c_begin] += w * w;
    }
  }
  std::vector<float> inv(n);
  for (int64_t i = 0; i < n; ++i) {
    // torch.istft rejects an envelope below 1e-11 (NOLA); here only positions that no window
    // covers can be that small (validate_nola() rejects gaps), and they carry no signal: 0.
    inv[i] = env[i] > 1e-11 ? static_cast<float>(1.0 / (double(n_fft_) * env[i])) : 0.0f;
  }
  return inv;
}

void StftEngine::overlap_add(const float* frames, int n_frames, int64_t c_begin, int64_t c_end,
                             const float* inv_env, int64_t block_begin, int64_t block_end,
                             float* out) const {
  const int64_t lo = std::max(c_begin, block_begin), hi = std::min(c_end, block_end);
  if (lo >= hi) return;
  float* o = out - c_begin;  // o[c] for OLA coordinate c
  std::fill(o + lo, o + hi, 0.0f);
  const int64_t t_first = std::max<int64_t>(0, floor_div(lo - se_, hop_) + 1);
  const int64_t t_last = std::min<int64_t>(n_frames - 1, floor_div(hi - sb_ - 1, hop_));
  const float* w = window_.data();
  for (int64_t t = t_first; t <= t_last; ++t) {
    const int64_t base = t * hop_;
    const int64_t a = std::max(lo, base + sb_), b = std::min(hi, base + se_);
    const float* f = frames + size_t(t) * frame_stride_ - base;
    const float* wb = w - base;
    for (int64_t c = a; c < b; ++c) o[c] += f[c] * wb[c];
  }
  const float* ie = inv_env - c_begin;
  for (int64_t c = lo; c < hi; ++c) o[c] *= ie[c];
}

// Overlap-adding windows of length win at hop must leave no position uncovered (torch.istft's
// NOLA check), otherwise those samples cannot be reconstructed.
void validate_nola(const StftEngine& e) {
  for (int s = 0; s < e.hop(); ++s) {
    double sum = 0.0;
    for (int j = s; j < e.n_fft(); j += e.hop()) sum += double(e.window()[j]) * e.window()[j];
    require(sum > 1e-11, "STFT parameters: hop_length " + std::to_string(e.hop()) +
                             " leaves gaps between the Hann windows (fails NOLA), so the inverse "
                             "STFT is undefined; use a hop_length below win_length");
  }
}

}  // namespace detail

using detail::StftEngine;

int stft_num_frames(size_t n, const StftParams& p) {
  const int64_t padded = int64_t(n) + (p.center ? 2 * (p.n_fft / 2) : 0);
  if (padded < p.n_fft || p.hop_length <= 0) return 0;
  return static_cast<int>(1 + (padded - p.n_fft) / p.hop_length);
}

Spectrogram stft(const std::vector<float>& signal, const StftParams& p) {
  const StftEngine e(p);
  const int64_t len = static_cast<int64_t>(signal.size());
  require(p.center || len >= p.n_fft, "stft: a signal of " + std::to_string(len) +
                                          " samples is shorter than n_fft " +
                                          std::to_string(p.n_fft) + " (and centring is off)");
  const int n_frames = stft_num_frames(signal.size(), p);
  const int n = p.n_fft;
  const int f_count = p.n_freq();

  Spectrogram out;
  out.n_freq = f_count;
  out.n_frames = n_frames;
  out.data.resize(size_t(f_count) * n_frames);

  // Frame t covers OLA coordinates [t·hop, t·hop + n_fft), i.e. signal samples from t·hop − offset.
  // Frames inside the signal read it in place; the few that reach into the centre padding gather
  // their reflected samples first.
  const int64_t off = e.offset();
  const int64_t hop = p.hop_length;
  const bool parallel = int64_t(n_frames) * n >= detail::kParallelSamples;
#pragma omp parallel if (parallel)
  {
    // Per thread: the windowed frame (zero outside the window support), its spectrum, and the
    // reflected samples of frames that reach into the centre padding.
    detail::AlignedFloats scratch = detail::alloc_floats(n);
    detail::AlignedFloats spec = detail::alloc_floats(e.spec_stride());
    std::vector<float> edge(n, 0.0f);
#pragma omp for schedule(dynamic, 8)
    for (int t = 0; t < n_frames; ++t) {
      const int64_t first = int64_t(t) * hop - off;  // signal index of the frame's sample 0
      if (first + e.support_begin() >= 0 && first + e.support_end() <= len) {
        e.forward_frame(signal.data() + first + e.support_begin(), scratch.get(), spec.get());
      } else {
        for (int j = 0; j < e.support_end() - e.support_begin(); ++j) {
          const int64_t k = first + e.support_begin() + j;
          edge[j] =
              len == 0 ? 0.0f : signal[(k >= 0 && k < len) ? k : detail::reflect_index(k, len)];
        }
        e.forward_frame(edge.data(), scratch.get(), spec.get());
      }
      const float* b = spec.get();
      for (int f = 0; f < f_count; ++f) out(f, t) = {b[2 * f], b[2 * f + 1]};
    }
  }
  return out;
}

std::vector<float> istft(const Spectrogram& spec, const StftParams& p,
                         std::optional<size_t> length) {
  const StftEngine e(p);
  detail::validate_nola(e);
  require(spec.n_freq == p.n_freq(), "istft: the spectrogram has " + std::to_string(spec.n_freq) +
                                         " frequency bins but n_fft " + std::to_string(p.n_fft) +
                                         " needs " + std::to_string(p.n_freq()));
  const int n_frames = spec.n_frames;
  const int64_t out_len =
      length ? int64_t(*length) : std::max<int64_t>(0, e.default_length(n_frames));
  std::vector<float> out(out_len, 0.0f);
  if (n_frames == 0 || out_len == 0) return out;

  const size_t stride = e.spec_stride();
  const int f_count = spec.n_freq;
  detail::AlignedFloats frames = detail::alloc_floats(size_t(n_frames) * e.frame_stride());
  const bool parallel = int64_t(n_frames) * p.n_fft >= detail::kParallelSamples;
#pragma omp parallel if (parallel)
  {
    detail::AlignedFloats b = detail::alloc_floats(stride);  // the spectrum, destroyed by c2r
#pragma omp for schedule(dynamic, 8)
    for (int t = 0; t < n_frames; ++t) {
      for (int f = 0; f < f_count; ++f) {
        const std::complex<float> v = spec(f, t);
        b[2 * f] = v.real();
        b[2 * f + 1] = v.imag();
      }
      e.inverse_frame(b.get(), frames.get() + size_t(t) * e.frame_stride());
    }
  }

  // Output sample i is OLA coordinate i + offset; beyond the last frame (length longer than the
  // frames reach) the output is zero-padded, as torch.istft does.
  const int64_t expected = p.n_fft + int64_t(p.hop_length) * (n_frames - 1);
  const int64_t c0 = e.offset();
  const int64_t c1 = std::min(c0 + out_len, expected);
  if (c1 <= c0) return out;
  const std::vector<float> inv_env = e.inverse_envelope(n_frames, c0, c1);
  const int64_t hop = p.hop_length;
  const int64_t n_blocks = (c1 + hop - 1) / hop;
#pragma omp parallel for schedule(dynamic, 8) if (parallel)
  for (int64_t k = c0 / hop; k < n_blocks; ++k) {
    e.overlap_add(frames.get(), n_frames, c0, c1, inv_env.data(), k * hop, (k + 1) * hop,
                  out.data());
  }
  return out;
}

Matrix magnitude(const Spectrogram& spec) {
  Matrix m(spec.n_freq, spec.n_frames);
  for (size_t i = 0; i < spec.data.size(); ++i) m.data[i] = std::abs(spec.data[i]);
  return m;
}

Matrix log_magnitude(const Spectrogram& spec, float eps) {
  Matrix m(spec.n_freq, spec.n_frames);
  for (size_t i = 0; i < spec.data.size(); ++i) m.data[i] = std::log(std::abs(spec.data[i]) + eps);
  return m;
}

}  // namespace neraf::dsp
