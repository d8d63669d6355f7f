#include "neraf/metrics/room_acoustics.h"

#include <cmath>

#include "neraf/dsp/filters.h"
#include "neraf/util/error.h"

namespace neraf::metrics {

std::string to_string(Variant variant) { return variant == Variant::raf ? "raf" : "soundspaces"; }

Variant parse_variant(const std::string& name, const std::string& what) {
  if (name == "soundspaces") return Variant::soundspaces;
  if (name == "raf") return Variant::raf;
  throw Error(what + ": unknown variant '" + name + "'; use 'soundspaces' or 'raf'");
}

double t60_decay_db(Variant variant) { return variant == Variant::raf ? 10.0 : 30.0; }

dsp::StftParams stft_params(Variant variant) {
  return variant == Variant::raf ? dsp::StftParams::raf() : dsp::StftParams::soundspaces();
}

int reference_sample_rate(Variant variant) { return variant == Variant::raf ? 48000 : 22050; }

const char* to_string(DecayStatus status) {
  switch (status) {
    case DecayStatus::ok:
      return "ok";
    case DecayStatus::silent:
      return "silent";
    case DecayStatus::no_decay:
      return "no decay";
  }
  return "?";
}

std::vector<double> schroeder_curve_db(const std::vector<float>& h) {
  const size_t n = h.size();
  std::vector<double> energy(n);
  double acc = 0.0;
  for (size_t i = n; i-- > 0;) {
    acc += double(h[i]) * double(h[i]);
    energy[i] = acc;
  }
  // Backward sums are non-increasing, so the last nonzero energy sits just before the zero tail.
  size_t last_nonzero = 0;
  bool any = false;
  for (size_t i = n; i-- > 0;) {
    if (energy[i] > 0.0) {
      last_nonzero = i;
      any = true;
      break;
    }
  }
  if (!any || last_nonzero == 0) return {};
  // The reference keeps energy[:i_nz] (exclusive). Convert to dB first and subtract E_dB[0] in a
  // second pass, as it does: curve[0] is then exactly 0 (no fused multiply-add across the two).
  std::vector<double> curve(last_nonzero);
  for (size_t i = 0; i < last_nonzero; ++i) curve[i] = 10.0 * std::log10(energy[i]);
  const double e0_db = curve[0];
  for (double& v : curve) v -= e0_db;
  return curve;
}

long first_index_below(const std::vector<double>& curve_db, double level_db) {
  for (size_t i = 0; i < curve_db.size(); ++i) {
    if (curve_db[i] < level_db) return static_cast<long>(i);
  }
  return -1;
}

namespace {

bool all_zero(const std::vector<float>& h) {
  for (float v : h) {
    if (v != 0.0f) return false;
  }
  return true;
}

DecayTime failed(DecayStatus status) { return {std::numeric_limits<double>::quiet_NaN(), status}; }

}  // namespace

DecayTime measure_t60(const std::vector<float>& h, double fs, double decay_db) {
  if (all_zero(h)) return failed(DecayStatus::silent);
  const std::vector<double> curve = schroeder_curve_db(h);
  const long i5 = first_index_below(curve, -5.0);
  const long i_decay = first_index_below(curve, -5.0 - decay_db);
  if (i5 < 0 || i_decay < 0) return failed(DecayStatus::no_decay);
  return {(60.0 / decay_db) * (double(i_decay) / fs - double(i5) / fs), DecayStatus::ok};
}

DecayTime measure_t60(const std::vector<float>& h, double fs, Variant variant) {
  if (variant == Variant::raf) {
    return measure_t60(dsp::highpass_biquad(h, fs, kRafHighpassHz, kRafHighpassQ), fs,
                       t60_decay_db(variant));
  }
  return measure_t60(h, fs, t60_decay_db(variant));
}

DecayTime measure_edt(const std::vector<float>& h, double fs) {
  if (all_zero(h)) return failed(DecayStatus::silent);
  const long i = first_index_below(schroeder_curve_db(h), -10.0);
  if (i < 0) return failed(DecayStatus::no_decay);
  return {(60.0 / 10.0) * (double(i) / fs), DecayStatus::ok};
}

long c50_split_sample(double fs) {
  // Same double arithmetic as the reference's int((time / 1000) * fs + 1) with time = 50.
  return static_cast<long>((50.0 / 1000.0) * fs + 1.0);
}

double measure_c50(const std::vector<float>& h, double fs) {
  const size_t split = static_cast<size_t>(std::max(0L, c50_split_sample(fs)));
  double early = 0.0, late = 0.0;
  for (size_t i = 0; i < h.size(); ++i) {
    const double p = double(h[i]) * double(h[i]);
    (i < split ? early : late) += p;
  }
  // IEEE: x/0 = inf, 0/x = 0 -> log10 = -inf, 0/0 = NaN (numpy's results, without its warning).
  return 10.0 * std::log10(early / late);
}

void require_finite_samples(const io::AudioBuffer& audio, const std::string& name) {
  for (size_t c = 0; c < audio.channels.size(); ++c) {
    const std::vector<float>& h = audio.channels[c];
    for (size_t i = 0; i < h.size(); ++i) {
      if (!std::isfinite(h[i])) {
        throw Error(name + ": channel " + std::to_string(c) + ", sample " + std::to_string(i) +
                    " is " + (std::isnan(h[i]) ? "NaN" : "infinite") +
                    "; metrics need finite samples (regenerate or fix the file)");
      }
    }
  }
}

std::vector<ChannelAcoustics> measure_room_acoustics(const io::AudioBuffer& rir, Variant variant,
                                                     const std::string& name) {
  require(rir.sample_rate > 0, name + ": sample rate must be positive");
  require_finite_samples(rir, name);
  std::vector<ChannelAcoustics> out;
  out.reserve(rir.channels.size());
  for (const auto& h : rir.channels) {
    ChannelAcoustics a;
    a.t60 = measure_t60(h, rir.sample_rate, variant);
    a.edt = measure_edt(h, rir.sample_rate);
    a.c50_db = measure_c50(h, rir.sample_rate);
    out.push_back(a);
  }
  return out;
}

}  // namespace neraf::metrics
