#pragma once
// Room-acoustic parameters of one impulse response (RIR) with the exact semantics of the published
// NeRAF evaluation (docs: neraf-reference.md §4.2-4.4), so our numbers compare with the paper's:
//   T60  two-point Schroeder estimate of pyroomacoustics 0.7.3 `measure_rt60`
//   EDT  6 × (time to −10 dB on the Schroeder curve)
//   C50  early/late energy ratio split at int(0.05·fs + 1) samples counted from sample 0
// All sums run in double precision (the reference runs numpy float32); on the real recordings in
// assets/real both give the same sample indices, so the same numbers.
#include <limits>
#include <string>
#include <vector>

#include "neraf/dsp/stft.h"
#include "neraf/io/audio_file.h"

namespace neraf::metrics {

// Which published evaluation recipe to follow. Only T60 and the STFT error depend on it.
enum class Variant {
  soundspaces,  // T60 full band, 30 dB decay; STFT n_fft 512, window 512, hop 128 (22.05 kHz data)
  raf,  // T60 after a 200 Hz biquad high-pass (Q 0.707, clamped), 10 dB decay; STFT n_fft 1024,
        // window 512, hop 256 (48 kHz data)
};

std::string to_string(Variant variant);  // "soundspaces" / "raf"
// Throws neraf::Error naming `what` (a flag or file) and the accepted names.
Variant parse_variant(const std::string& name, const std::string& what = "--variant");
double t60_decay_db(Variant variant);          // 30 / 10
dsp::StftParams stft_params(Variant variant);  // StftParams::soundspaces() / raf()
int reference_sample_rate(Variant variant);    // 22050 / 48000: the rate the paper evaluates at

// RAF's T60 pre-filter (torchaudio highpass_biquad defaults).
constexpr double kRafHighpassHz = 200.0;
constexpr double kRafHighpassQ = 0.707;

// Why a decay time has no value.
enum class DecayStatus {
  ok,
  silent,    // no energy at all (all-zero signal)
  no_decay,  // the Schroeder curve never falls below the level the estimate needs
};

struct DecayTime {
  double seconds = std::numeric_limits<double>::quiet_NaN();  // meaningful only when ok
  DecayStatus status = DecayStatus::ok;

  bool valid() const { return status == DecayStatus::ok; }
  // The value the reference stores for this measurement: T60 invalid -> -1 (its try/except);
  // EDT of silence -> NaN. (An EDT that never reaches -10 dB aborts the reference run; we use NaN.)
  double reference_t60() const { return valid() ? seconds : -1.0; }
  double reference_edt() const {
    return valid() ? seconds : std::numeric_limits<double>::quiet_NaN();
  }
};

const char* to_string(DecayStatus status);  // "ok" / "silent" / "no decay"

// Schroeder energy decay curve in dB: E[n] = sum_{m>=n} h[m]^2, cut before the LAST sample with
// nonzero energy (the reference's `energy[:i_nz]`, which drops that sample too), then
// 10·log10(E) − 10·log10(E[0]) so that curve[0] = 0 dB. Empty when no sample after the first is
// nonzero (the reference then fails on an empty curve).
std::vector<double> schroeder_curve_db(const std::vector<float>& h);

// First index whose value is strictly below `level_db` (the reference's `np.min(np.where(...))`),
// or -1 when there is none.
long first_index_below(const std::vector<double>& curve_db, double level_db);

// pyroomacoustics 0.7.3 measure_rt60: i5 = first index below −5 dB, iD = first index below
// −5 − decay_db dB, T60 = (60 / decay_db)·(iD − i5) / fs. Full band, no filtering.
DecayTime measure_t60(const std::vector<float>& h, double fs, double decay_db);

// The variant's T60: soundspaces = measure_t60(h, fs, 30); raf = 200 Hz high-pass (dsp's
// torchaudio-exact biquad, output clamped to [−1, 1]) then measure_t60(·, fs, 10).
DecayTime measure_t60(const std::vector<float>& h, double fs, Variant variant);

// EDT = 6·i/fs with i the first index below −10 dB (the raw signal for both variants).
DecayTime measure_edt(const std::vector<float>& h, double fs);

// Index where C50's late part starts: int(0.05·fs + 1) (1103 at 22.05 kHz, 2401 at 48 kHz).
long c50_split_sample(double fs);

// C50 = 10·log10(sum_{n<t} h^2 / sum_{n>=t} h^2) dB (raw signal for both variants). Zero energy
// follows IEEE arithmetic as numpy does in the reference: no late energy -> +inf, no early energy
// -> −inf, no energy at all -> NaN. Never throws.
double measure_c50(const std::vector<float>& h, double fs);

struct ChannelAcoustics {
  DecayTime t60;  // the variant's T60
  DecayTime edt;
  double c50_db = 0.0;
};

// Throws neraf::Error naming `name`, the channel and the sample when a sample is NaN or infinite
// (the measurements would silently turn into "no decay"/NaN otherwise).
void require_finite_samples(const io::AudioBuffer& audio, const std::string& name);

// Per channel T60 / EDT / C50 of a (multi-channel) RIR at its own sample rate. [n_channels]
// neraf::Error naming `name` for a non-positive sample rate or non-finite samples.
std::vector<ChannelAcoustics> measure_room_acoustics(const io::AudioBuffer& rir, Variant variant,
                                                     const std::string& name = "impulse response");

}  // namespace neraf::metrics
