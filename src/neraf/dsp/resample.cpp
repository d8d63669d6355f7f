#include "neraf/dsp/resample.h"

#include <samplerate.h>

#include <cmath>
#include <string>

#include "neraf/util/error.h"

namespace neraf::dsp {

namespace {

void check_rates(double from_hz, double to_hz) {
  require(from_hz > 0.0 && to_hz > 0.0, "resample: sample rates must be positive (got " +
                                            std::to_string(from_hz) + " Hz -> " +
                                            std::to_string(to_hz) + " Hz)");
  const double ratio = to_hz / from_hz;
  // libsamplerate's limit on the conversion ratio.
  require(ratio >= 1.0 / 256.0 && ratio <= 256.0,
          "resample: cannot convert " + std::to_string(from_hz) + " Hz to " +
              std::to_string(to_hz) + " Hz (ratio beyond 1:256)");
}

}  // namespace

std::vector<float> resample(const std::vector<float>& x, double from_hz, double to_hz) {
  check_rates(from_hz, to_hz);
  const double ratio = to_hz / from_hz;
  const size_t out_len = static_cast<size_t>(std::llround(double(x.size()) * ratio));
  if (from_hz == to_hz) return x;
  if (x.empty()) return {};

  // One call over the whole signal (src_simple flushes the filter at the end of input), into a
  // buffer with a little slack; then exactly round(n·to/from) samples are kept, zero-padding the
  // at most few samples libsamplerate leaves out at the very end.
  std::vector<float> out(out_len + 16, 0.0f);
  SRC_DATA d{};
  d.data_in = x.data();
  d.input_frames = static_cast<long>(x.size());
  d.data_out = out.data();
  d.output_frames = static_cast<long>(out.size());
  d.src_ratio = ratio;
  const int rc = src_simple(&d, SRC_SINC_BEST_QUALITY, 1);
  require(rc == 0, std::string("resample: libsamplerate failed: ") + src_strerror(rc));
  out.resize(out_len);
  if (static_cast<size_t>(d.output_frames_gen) < out_len) {
    std::fill(out.begin() + d.output_frames_gen, out.end(), 0.0f);
  }
  return out;
}

io::AudioBuffer resample(const io::AudioBuffer& audio, int to_hz) {
  io::AudioBuffer out;
  check_rates(audio.sample_rate, to_hz);  // before the parallel loop: nothing may throw inside
  out.sample_rate = to_hz;
  out.channels.resize(audio.channels.size());
  const int n_ch = audio.num_channels();
  // Channels are independent conversions (libsamplerate keeps no shared state).
#pragma omp parallel for schedule(static) if (n_ch > 1)
  for (int c = 0; c < n_ch; ++c) {
    out.channels[c] = resample(audio.channels[c], audio.sample_rate, to_hz);
  }
  return out;
}

}  // namespace neraf::dsp
