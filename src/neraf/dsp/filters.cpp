#include "neraf/dsp/filters.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "neraf/util/error.h"

namespace neraf::dsp {

std::vector<float> highpass_biquad(const std::vector<float>& x, double sample_rate,
                                   double cutoff_hz, double q) {
  require(sample_rate > 0.0, "highpass_biquad: sample rate must be positive");
  require(cutoff_hz > 0.0 && cutoff_hz < sample_rate / 2.0,
          "highpass_biquad: cutoff " + std::to_string(cutoff_hz) + " Hz must lie in (0, " +
              std::to_string(sample_rate / 2.0) + ") Hz");
  require(q > 0.0, "highpass_biquad: Q must be positive");

  // torchaudio computes the coefficients on float32 tensors (w0 = 2π·f/fs with f a float32 tensor)
  // and filters in float32; the same rounding is kept here so T60 thresholds land on the same
  // samples.
  const float w0 = static_cast<float>(2.0 * M_PI) * static_cast<float>(cutoff_hz) /
                   static_cast<float>(sample_rate);
  const float cw = std::cos(w0);
  const float alpha = std::sin(w0) / 2.0f / static_cast<float>(q);
  const float b0 = (1.0f + cw) / 2.0f;
  const float b1 = -1.0f - cw;
  const float b2 = b0;
  const float a0 = 1.0f + alpha;
  const float a1 = -2.0f * cw;
  const float a2 = 1.0f - alpha;
  // lfilter: the FIR part is divided by a0, the feedback coefficients are normalised by a0.
  const float na1 = a1 / a0, na2 = a2 / a0;

  const size_t n = x.size();
  std::vector<float> y(n);
  float x1 = 0.0f, x2 = 0.0f, y1 = 0.0f, y2 = 0.0f;  // zero initial state (lfilter pads zeros)
  for (size_t i = 0; i < n; ++i) {
    const float fir = (b2 * x2 + b1 * x1 + b0 * x[i]) / a0;
    // Same accumulation order as torchaudio's CPU loop: subtract the oldest output term first.
    float out = fir;
    out -= y2 * na2;
    out -= y1 * na1;
    y[i] = out;
    x2 = x1;
    x1 = x[i];
    y2 = y1;
    y1 = out;
  }
  // clamp=True clamps the final output, not the recursion state.
  for (float& v : y) v = std::clamp(v, -1.0f, 1.0f);
  return y;
}

}  // namespace neraf::dsp
