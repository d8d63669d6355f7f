#include "neraf/dsp/auralize.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "neraf/dsp/convolve.h"
#include "neraf/util/error.h"

namespace neraf::dsp {

int auralized_channels(int rir_channels, int dry_channels) {
  if (rir_channels <= 0 || dry_channels <= 0) return 0;
  if (dry_channels == 1) return rir_channels;
  if (rir_channels == 1 || rir_channels == dry_channels) return dry_channels;
  return 0;
}

io::AudioBuffer auralize(const io::AudioBuffer& rir, const io::AudioBuffer& dry) {
  require(rir.num_frames() > 0, "auralize: the impulse response is empty");
  require(dry.num_frames() > 0, "auralize: the dry audio is empty");
  require(rir.sample_rate == dry.sample_rate,
          "auralize: the dry audio is at " + std::to_string(dry.sample_rate) +
              " Hz but the impulse response at " + std::to_string(rir.sample_rate) +
              " Hz; resample the dry audio first");
  const int n_out = auralized_channels(rir.num_channels(), dry.num_channels());
  require(n_out > 0,
          "auralize: cannot combine a " + std::to_string(rir.num_channels()) +
              "-channel impulse response with " + std::to_string(dry.num_channels()) +
              "-channel dry audio (use mono dry audio, a mono RIR, or equal channel counts)");

  io::AudioBuffer out;
  out.sample_rate = rir.sample_rate;
  out.channels.resize(n_out);
  // Output channels are independent convolutions; nothing inside the loop throws.
#pragma omp parallel for schedule(static) if (n_out > 1)
  for (int c = 0; c < n_out; ++c) {
    const auto& h = rir.channels[rir.num_channels() == 1 ? 0 : c];
    const auto& x = dry.channels[dry.num_channels() == 1 ? 0 : c];
    out.channels[c] = fft_convolve(x, h);
  }
  return out;
}

float peak_abs(const io::AudioBuffer& audio) {
  float peak = 0.0f;
  for (const auto& ch : audio.channels) {
    for (float v : ch) peak = std::max(peak, std::abs(v));
  }
  return peak;
}

float normalize_peak(io::AudioBuffer& audio, float target) {
  const float peak = peak_abs(audio);
  if (!(peak > 0.0f) || !std::isfinite(peak)) return 1.0f;
  const float gain = target / peak;
  for (auto& ch : audio.channels) {
    for (float& v : ch) v *= gain;
  }
  return gain;
}

}  // namespace neraf::dsp
