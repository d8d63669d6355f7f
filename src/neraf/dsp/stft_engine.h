#pragma once
// Internal to dsp (not part of the public API): the pieces stft(), istft() and griffin_lim() share,
// working on frame-major buffers ([n_frames][stride] floats, one in-place FFT buffer per frame) so
// frames can be transformed independently and in parallel.
//
// Coordinates: "OLA coordinates" c index the (virtually) centre-padded signal, frame t covers
// [t·hop, t·hop + n_fft); output sample i of a centred istft is c = i + n_fft/2.
#include <cstdint>
#include <vector>

#include "neraf/dsp/fft_plans.h"
#include "neraf/dsp/stft.h"

namespace neraf::dsp::detail {

// Throws neraf::Error for parameters torch would reject.
void validate(const StftParams& p);

class StftEngine {
 public:
  explicit StftEngine(const StftParams& p);

  int n_fft() const { return n_fft_; }
  int n_freq() const { return n_freq_; }
  int hop() const { return hop_; }
  // The window's nonzero support inside a frame: [support_begin, support_end).
  int support_begin() const { return sb_; }
  int support_end() const { return se_; }
  // Floats per spectrum buffer (n_freq interleaved complex values) and per real frame buffer
  // (n_fft samples), both rounded up so consecutive buffers keep FFTW's alignment.
  size_t spec_stride() const { return spec_stride_; }
  size_t frame_stride() const { return frame_stride_; }
  const std::vector<float>& window() const { return window_; }  // [n_fft], zero-padded centrally
  int offset() const { return center_ ? n_fft_ / 2 : 0; }       // output index 0 <-> OLA coordinate

  // Default istft length for n_frames frames (torch: n_fft + hop·(T−1) minus the centre trim).
  int64_t default_length(int n_frames) const;

  // Windows the frame's samples under the window support, support[0 .. support_end −
  // support_begin) (support[0] is frame sample support_begin), into `scratch` and transforms it to
  // n_freq interleaved complex values in `spec`. scratch: an aligned buffer of n_fft floats that is
  // zero outside the window support; only the support is written (and the out-of-place r2c
  // preserves its input), so it stays reusable without clearing.
  void forward_frame(const float* support, float* scratch, float* spec) const;
  // Inverse transform of n_freq complex values (destroyed) to n_fft real samples (unnormalised).
  void inverse_frame(float* spec, float* frame) const;

  // 1 / (n_fft · Σ_t w²[c − t·hop]) for c in [c_begin, c_end): the factor that turns the
  // overlap-added frames into torch.istft's output. Where the envelope is below 1e-11 (outside
  // every frame's window) the factor is 0.
  std::vector<float> inverse_envelope(int n_frames, int64_t c_begin, int64_t c_end) const;

  // out[c − c_begin] = inv_env[c − c_begin] · Σ_t w[c − t·hop] · frames[t][c − t·hop] for c in
  // [c_begin, c_end) ∩ [block_begin, block_end) (sum in increasing t: deterministic).
  // frames: n_frames real frames from inverse_frame(), frame_stride() floats apart.
  void overlap_add(const float* frames, int n_frames, int64_t c_begin, int64_t c_end,
                   const float* inv_env, int64_t block_begin, int64_t block_end, float* out) const;

 private:
  int n_fft_, n_freq_, hop_, sb_, se_;
  bool center_;
  size_t spec_stride_, frame_stride_;
  std::vector<float> window_;
  fftwf_plan r2c_, c2r_;
};

// Whether the cores look busy with other work (1-minute load average above the number of cores
// OpenMP may use). Parallel regions are then skipped where they synchronise often: a thread
// waiting at a barrier for a descheduled partner costs milliseconds per barrier (measured: a
// 2-thread Griffin-Lim took 0.8 s instead of 4 ms at load 10 on 2 cores).
bool cores_busy();

// Throws neraf::Error when windows at this hop leave gaps (NOLA fails): no inverse STFT exists.
void validate_nola(const StftEngine& e);

// Maps an index of the centre-padded signal to the signal (reflection without repeating the edge
// sample, as torch's reflect padding; repeated for pads longer than the signal, as numpy does).
inline int64_t reflect_index(int64_t j, int64_t len) {
  if (len <= 1) return 0;
  const int64_t period = 2 * (len - 1);
  j = j < 0 ? -j : j;
  j %= period;
  return j < len ? j : period - j;
}

}  // namespace neraf::dsp::detail
