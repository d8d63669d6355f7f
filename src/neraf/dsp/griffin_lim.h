#pragma once
// Griffin-Lim phase reconstruction as torchaudio.functional.griffinlim (what NeRAF evaluates with):
// momentum m = momentum/(1+momentum) (fast Griffin-Lim); initial phase: real and imaginary parts
// each uniform in [0, 1) from `seed` (rand_init) or all ones; 32 iterations of
// { x = istft(S·a); r = stft(x); a = r − m·prev; a /= |a| + 1e-16; prev = r }; final istft(S·a).
#include <cstdint>
#include <optional>

#include "neraf/dsp/stft.h"

namespace neraf::dsp {

struct GriffinLimOptions {
  int n_iter = 32;
  float momentum = 0.99f;
  bool rand_init = true;
  uint64_t seed = 0;
  std::optional<size_t> length;  // output length; default hop*(T-1)
};

// magnitude: [n_freq, n_frames] linear magnitude (power 1).
std::vector<float> griffin_lim(const Matrix& magnitude, const StftParams& p,
                               const GriffinLimOptions& options = {});

}  // namespace neraf::dsp
