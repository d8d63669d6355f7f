#pragma once
// Griffin-Lim of the runtime: the same arithmetic as neraf::dsp::griffin_lim (torchaudio's fast
// Griffin-Lim: momentum 0.99, centred STFT with reflect padding, length hop·(T−1)) on buffers
// allocated once, so a query allocates nothing. The plans and tables are immutable and shared
// (GriffinLim, owned by the Engine); each channel being reconstructed needs its own
// GriffinLimBuffers (owned by a Workspace).
//
// Same result as dsp::griffin_lim for the same magnitudes and seed: the same FFTW plans
// (FFTW_ESTIMATE, out-of-place, equally aligned arrays), the same frame-major buffers and the
// same per-frame order of operations (see dsp/griffin_lim.cpp, which this follows step by step).
#include <fftw3.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace neraf::rt {

struct FftwDeleter {
  void operator()(float* p) const noexcept { fftwf_free(p); }
};
// A zero-initialised float array from fftwf_malloc (aligned as FFTW's SIMD codelets want).
using FftwFloats = std::unique_ptr<float[], FftwDeleter>;
FftwFloats alloc_fftw_floats(size_t n);  // throws std::bad_alloc

// One channel's state.
struct GriffinLimBuffers {
  FftwFloats spec;          // [T][spec_stride]: r = stft(x), then S·a (interleaved complex)
  FftwFloats frames;        // [T][frame_stride]: irfft(S·a), read by the overlap-add
  FftwFloats scratch;       // [n_fft]: the windowed frame (zero outside the window support)
  std::vector<float> prev;  // [T][2F]: the previous rebuilt spectrum (torchaudio's tprev)
  std::vector<float> mag;   // [T][F]: the target magnitude, frame-major
  std::vector<float> sig;   // the signal at OLA coordinates (centre-padded by n_fft/2 each side)
  std::vector<float> edge;  // [n_fft]: reflected samples of frames reaching into the padding
};

class GriffinLim {
 public:
  static constexpr float kMomentum = 0.99f;

  GriffinLim(int n_fft, int win_length, int hop_length, int n_frames);
  ~GriffinLim();
  GriffinLim(const GriffinLim&) = delete;
  GriffinLim& operator=(const GriffinLim&) = delete;

  int n_freq() const { return n_freq_; }
  int n_frames() const { return n_frames_; }
  // Samples of the reconstruction: n_fft + hop·(T−1) − 2·(n_fft/2) (torch.istft's default).
  int64_t length() const { return length_; }
  // Floats per frame of the initial phase table (see random_phases).
  size_t phase_stride() const { return 2 * size_t(n_freq_); }

  GriffinLimBuffers make_buffers() const;

  // The initial phases of channels [0, channels) as torch.rand(C, F, T, complex) after
  // manual_seed(seed) on the CPU generator (dsp::griffin_lim's recipe): mt19937 seeded with the
  // low 32 bits, each value (draw & 0xFFFFFF)·2^-24, drawn in [c][f][t][re, im] order. Stored
  // frame-major for the reconstruction: out[((c·T + t)·F + f)·2 + {0, 1}].
  void random_phases(uint64_t seed, int channels, float* out) const;

  // One channel. mag: [F, T] linear magnitudes (row-major, as the log-STFT); phases: this
  // channel's [T][2F] slice of random_phases; out: out_len samples (the reconstruction cut or
  // zero-padded to out_len).
  void run(const float* mag, const float* phases, int n_iter, GriffinLimBuffers& b, float* out,
           int64_t out_len) const;

 private:
  void forward_frame(const float* support, float* scratch, float* spec) const;
  void overlap_add(const float* frames, int64_t block_begin, int64_t block_end, float* out) const;

  int n_fft_, n_freq_, hop_, n_frames_, sb_, se_;
  int64_t length_, c0_, c1_, sig_len_, n_blocks_, block_first_;
  size_t spec_stride_, frame_stride_;
  std::vector<float> window_;   // [n_fft]
  std::vector<float> inv_env_;  // [c1 − c0]: 1/(n_fft·Σ_t w²) at OLA coordinates [c0, c1)
  fftwf_plan r2c_ = nullptr, c2r_ = nullptr;
};

}  // namespace neraf::rt
