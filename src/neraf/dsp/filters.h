#pragma once
// Biquad filters with torchaudio semantics (RBJ cookbook coefficients, direct-form lfilter whose
// output is clamped to [-1, 1], as torchaudio.functional.lfilter(clamp=True)).
#include <vector>

namespace neraf::dsp {

std::vector<float> highpass_biquad(const std::vector<float>& x, double sample_rate,
                                   double cutoff_hz, double q = 0.707);

}  // namespace neraf::dsp
