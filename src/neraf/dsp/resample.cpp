#include "neraf/dsp/resample.h"

#include <soxr.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "neraf/util/error.h"

namespace neraf::dsp {

namespace {

void check_rates(double from_hz, double to_hz) {
  char rates[96];
  std::snprintf(rates, sizeof rates, "%g Hz to %g Hz", from_hz, to_hz);
  require(from_hz > 0.0 && to_hz > 0.0,
          std::string("cannot resample ") + rates + ": sample rates must be positive");
  const double ratio = to_hz / from_hz;
  // A sane bound on the conversion ratio (soxr allows more; nothing here needs it).
  require(ratio >= 1.0 / 256.0 && ratio <= 256.0,
          std::string("cannot resample ") + rates +
              " (the rates may be at most 256x apart); convert the audio to a usual rate first");
}

}  // namespace

std::vector<float> resample(const std::vector<float>& x, double from_hz, double to_hz) {
  check_rates(from_hz, to_hz);
  if (from_hz == to_hz) return x;
  if (x.empty()) return {};
  // ceil(n·to/from), exactly when both rates are whole numbers (the usual case).
  const double n = static_cast<double>(x.size());
  size_t out_len = 0;
  if (from_hz == std::floor(from_hz) && to_hz == std::floor(to_hz) && from_hz < 1e9 &&
      to_hz < 1e9) {
    const auto from = static_cast<unsigned long long>(from_hz);
    const auto to = static_cast<unsigned long long>(to_hz);
    out_len = static_cast<size_t>((x.size() * to + from - 1) / from);
  } else {
    out_len = static_cast<size_t>(std::ceil(n * (to_hz / from_hz)));
  }
  std::vector<float> out(out_len, 0.0f);
  // One call over the whole signal; soxr flushes its filter at the end of input and compensates
  // its delay, so out[k] is aligned with x at time k / to_hz. The at most few samples it leaves
  // out at the very end stay zero.
  const soxr_quality_spec_t quality = soxr_quality_spec(SOXR_HQ, 0);
  const soxr_io_spec_t io = soxr_io_spec(SOXR_FLOAT32_I, SOXR_FLOAT32_I);
  size_t done = 0;
  const soxr_error_t error = soxr_oneshot(from_hz, to_hz, 1, x.data(), x.size(), nullptr,
                                          out.data(), out.size(), &done, &io, &quality, nullptr);
  require(!error, std::string("resample: libsoxr failed: ") + soxr_strerror(error));
  return out;
}

io::AudioBuffer resample(const io::AudioBuffer& audio, int to_hz) {
  io::AudioBuffer out;
  check_rates(audio.sample_rate, to_hz);  // before the parallel loop: nothing may throw inside
  out.sample_rate = to_hz;
  out.channels.resize(audio.channels.size());
  const int n_ch = audio.num_channels();
  // Channels are independent conversions (soxr_oneshot keeps no shared state).
#pragma omp parallel for schedule(static) if (n_ch > 1)
  for (int c = 0; c < n_ch; ++c) {
    out.channels[c] = resample(audio.channels[c], audio.sample_rate, to_hz);
  }
  return out;
}

}  // namespace neraf::dsp
