#include "neraf/data/rir_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "neraf/data/rir_layouts.h"
#include "neraf/util/error.h"

namespace neraf::data::detail {

bool sane_coordinates(const double* v, int n) {
  for (int k = 0; k < n; ++k)
    if (!(std::abs(v[k]) <= kMaxAbsCoordinate)) return false;  // NaN fails too
  return true;
}

namespace {

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", s);
  return buf;
}

std::string gigabytes(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f GB", bytes / 1e9);
  return buf;
}

}  // namespace

double cache_bytes(const RirSet& set, int64_t max_len, bool half) {
  return double(set.size()) * double(max_len) * double(set.channels) * double(set.n_freq) *
         (half ? 2.0 : 4.0);
}

RirHeader check_rir_header(const RirSet& set, int64_t i, ProblemList& problems) {
  const Rir& rir = set.rirs[static_cast<size_t>(i)];
  const bool ss = set.layout == AudioLayout::soundspaces;
  RirHeader h;
  h.probe = probe_audio(rir.wav_path);
  const AudioProbe& p = h.probe;
  bool wav_ok = p.ok;
  if (!p.ok) {
    problems.error_from_message(rir.wav_path, p.error);
  } else {
    if (p.sample_rate != set.wav_sample_rate) {
      problems.error(rir.wav_path,
                     "sample rate " + std::to_string(p.sample_rate) + " Hz, expected " +
                         std::to_string(set.wav_sample_rate) + " Hz",
                     std::string("resample it to ") + (ss ? "44.1" : "48") + " kHz");
      wav_ok = false;
    }
    if (p.channels != set.channels) {
      problems.error(rir.wav_path,
                     std::to_string(p.channels) + " channel(s), expected " +
                         std::to_string(set.channels) + (ss ? " (binaural)" : " (mono)"),
                     ss ? "SoundSpaces RIRs must be 2-channel binaural files"
                        : "RAF RIRs must be mono; keep one channel");
      wav_ok = false;
    }
    if (p.frames == 0) {
      problems.warning(rir.wav_path, "holds no samples (treated as silence, like the reference)",
                       "restore the file if it should not be empty");
    } else if (p.sample_rate > 0 && p.duration_s() > kMaxRirSeconds) {
      // The estimate says what accepting it would cost with SoundSpaces' padding to the longest.
      const int64_t frames = ss ? soundspaces_num_frames(p.frames) : kRafMaxLen;
      problems.error(
          rir.wav_path,
          seconds(p.duration_s()) + " long, more than the " + seconds(kMaxRirSeconds) +
              " an impulse response can last" +
              (ss ? " (padding all " + std::to_string(set.size()) + " RIRs to it would make a " +
                        gigabytes(cache_bytes(set, frames, false)) + " feature cache)"
                  : std::string()),
          "cut it to its decay or remove it from the split");
      wav_ok = false;
    } else if (!ss && p.frames < kRafSamples) {
      problems.warning(rir.wav_path,
                       "shorter than 0.32 s (" + std::to_string(p.frames) + " samples)",
                       "it is zero-padded to 15360 samples");
    }
  }
  if (!rir.magnitude_path.empty()) {
    try {
      const io::NpyHeader nh = io::read_npy_header(rir.magnitude_path);
      if (nh.shape.size() != 3 || nh.shape[0] != 2 || nh.shape[1] != set.n_freq ||
          nh.shape[2] < 1) {
        problems.error(rir.magnitude_path, "magnitudes must have shape [2, 257, T]",
                       "re-create it, or delete binaural_magnitudes_sr22050/ to use the wavs");
      } else {
        const double s = double(nh.shape[2]) * set.stft.hop_length / set.sample_rate;
        if (s > kMaxRirSeconds) {
          problems.error(rir.magnitude_path,
                         std::to_string(nh.shape[2]) + " frames (" + seconds(s) +
                             "), more than the " + seconds(kMaxRirSeconds) +
                             " an impulse response can last (padding all " +
                             std::to_string(set.size()) + " RIRs to it would make a " +
                             gigabytes(cache_bytes(set, nh.shape[2], false)) + " feature cache)",
                         "re-create it from a shorter RIR or remove the RIR from the split");
        } else {
          h.stft_frames = nh.shape[2];
        }
      }
    } catch (const Error& e) {
      problems.error_from_message(rir.magnitude_path, e.what());
    }
  } else if (wav_ok) {
    h.stft_frames = ss ? soundspaces_num_frames(p.frames) : kRafMaxLen;
  }
  return h;
}

void check_rir_samples(const std::string& wav, const std::vector<std::vector<float>>& channels,
                       ProblemList& problems) {
  bool any = false, all_zero = true;
  for (const auto& ch : channels) {
    any = any || !ch.empty();
    for (const float v : ch)
      if (v != 0.0f) {
        all_zero = false;
        break;
      }
    if (!all_zero) break;
  }
  // An empty file is reported by the header check already.
  if (any && all_zero)
    problems.warning(wav, "every sample is zero (treated as silence)",
                     "restore the file if the source should be audible there");
}

void check_magnitudes(const std::string& npy, const io::NpyArray& a, int64_t n_freq,
                      ProblemList& problems) {
  if (a.shape.size() != 3 || a.shape[0] != 2 || a.shape[1] != n_freq || a.shape[2] < 1) {
    problems.error(npy, "magnitudes must have shape [2, 257, T]",
                   "re-create it, or delete binaural_magnitudes_sr22050/ to use the wavs");
    return;
  }
  for (size_t k = 0; k < a.data.size(); ++k) {
    const float v = a.data[k];
    if (std::isfinite(v) && v >= 0 && v <= kMaxMagnitude) continue;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
    problems.error(npy,
                   "magnitude " + std::to_string(k) + " is " + buf +
                       (std::isfinite(v) ? (v < 0 ? " (negative)" : " (implausibly large)") : "") +
                       "; magnitudes are finite and non-negative",
                   "re-create the file, or delete binaural_magnitudes_sr22050/ to compute the "
                   "features from the wavs");
    return;
  }
}

void check_padded_cache_size(const RirSet& set, const std::vector<int64_t>& frames, bool half,
                             ProblemList& problems) {
  int64_t longest = -1, total = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (frames[i] <= 0) continue;
    total += frames[i];
    if (longest < 0 || frames[i] > frames[size_t(longest)]) longest = static_cast<int64_t>(i);
  }
  if (longest < 0) return;
  const int64_t max_len = frames[size_t(longest)];
  const double padded = cache_bytes(set, max_len, half);
  const double own = double(total) * set.channels * set.n_freq * (half ? 2 : 4);
  if (padded < kPaddingCheckBytes || padded <= kMaxPaddingFactor * own) return;
  const Rir& rir = set.rirs[size_t(longest)];
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "the longest RIR (%lld frames) makes the feature cache %.1f GB, %.0fx the %.2f GB "
                "the features need, because every RIR is padded to it",
                static_cast<long long>(max_len), padded / 1e9, padded / own, own / 1e9);
  problems.error(rir.magnitude_path.empty() ? rir.wav_path : rir.magnitude_path, buf,
                 "cut it to its decay or remove it from the split");
}

ProblemList check_rir_headers(const RirSet& set, std::vector<RirHeader>& headers) {
  const int64_t n = set.size();
  headers.assign(static_cast<size_t>(n), {});
  std::vector<ProblemList> per(static_cast<size_t>(n));
  parallel_for_each(n, [&](int64_t i) { headers[i] = check_rir_header(set, i, per[i]); });
  ProblemList all;
  for (const ProblemList& p : per) all.append(p.items());
  return all;
}

}  // namespace neraf::data::detail
