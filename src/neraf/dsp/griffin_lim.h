#pragma once
// Griffin-Lim phase reconstruction as torchaudio.functional.griffinlim (what NeRAF evaluates with):
// momentum m = momentum/(1+momentum) (fast Griffin-Lim); initial phase: real and imaginary parts
// each uniform in [0, 1) from `seed` (rand_init) or all ones; 32 iterations of
// { x = istft(S·a); r = stft(x); a = r − m·prev; a /= |a| + 1e-16; prev = r }; final istft(S·a).
#include <cstdint>
#include <optional>
#include <vector>

#include "neraf/dsp/stft.h"

namespace neraf::dsp {

struct GriffinLimOptions {
  int n_iter = 32;
  float momentum = 0.99f;
  bool rand_init = true;
  uint64_t seed = 0;
  std::optional<size_t> length;  // output length; default hop*(T-1)
  // 0: automatic — the OpenMP threads, unless called inside a parallel region (callers that
  // reconstruct many RIRs should parallelise over RIRs) or the cores are already busy (1-minute
  // load average above the core count: barriers then cost milliseconds each). 1: this thread
  // only. n > 1: up to n threads, always. The result is the same in every case.
  int threads = 0;
};

// magnitude: [n_freq, n_frames] linear magnitude (power 1). Returns the waveform, length
// options.length or hop·(T−1). p.center must be true (torchaudio's griffinlim always centres).
//
// The initial phases follow the recipe of torch's CPU generator for torch.rand(complex) after
// torch.manual_seed(seed) (not verified against torch here; NeRAF itself draws them on CUDA):
// std::mt19937 seeded with the low 32 bits of `seed`, each value (next() & 0xFFFFFF)·2^-24, drawn
// in memory order [freq][frame][re, im].
// `length` is used inside the iterations as torchaudio does when 1 + length/hop == n_frames (the
// only lengths torch accepts there); any other length only pads/cuts the final waveform.
// Results do not depend on the number of threads (frames run in parallel, sums in a fixed order).
std::vector<float> griffin_lim(const Matrix& magnitude, const StftParams& p,
                               const GriffinLimOptions& options = {});

// Several channels of one spectrogram (e.g. binaural [2, F, T]); all must have the same shape.
// The initial phases are drawn as for one [C, F, T] tensor: channel 0 first, then channel 1, ...
// (so channel 0 equals the single-channel call with the same seed). All channels' frames share one
// OpenMP work pool.
std::vector<std::vector<float>> griffin_lim(const std::vector<Matrix>& magnitudes,
                                            const StftParams& p,
                                            const GriffinLimOptions& options = {});

}  // namespace neraf::dsp
