// `neraf metrics`: room-acoustic parameters of one RIR file, or the errors of a predicted RIR
// against the ground truth, with the published NeRAF evaluation semantics (src/neraf/metrics/).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/io/audio_file.h"
#include "neraf/metrics/rir_errors.h"
#include "neraf/metrics/room_acoustics.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::cli {

namespace {

struct MetricsArgs {
  std::string rir;
  std::string pred;
  std::string gt;
  std::string variant = "soundspaces";
  bool json = false;
};

// JSON has no inf/NaN: a value that does not exist is null.
nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

std::string format_value(double v, const char* fmt) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::string format_decay(const metrics::DecayTime& d) {
  if (d.valid()) return format_value(d.seconds, "%.6f");
  return std::string("invalid (") + metrics::to_string(d.status) + ")";
}

std::string variant_summary(metrics::Variant v) {
  return v == metrics::Variant::raf ? "raf (T60: 200 Hz high-pass, 10 dB decay; STFT 1024/512/256)"
                                    : "soundspaces (T60: full band, 30 dB decay; STFT 512/512/128)";
}

void note_sample_rate(int fs, metrics::Variant v) {
  if (fs != metrics::reference_sample_rate(v)) {
    info("note: the paper evaluates the " + metrics::to_string(v) + " variant at " +
         std::to_string(metrics::reference_sample_rate(v)) + " Hz; these numbers use the file's " +
         std::to_string(fs) + " Hz");
  }
}

void run_single(const MetricsArgs& args, metrics::Variant variant) {
  const io::AudioBuffer rir = io::read_audio(args.rir);
  const auto acoustics = metrics::measure_room_acoustics(rir, variant, args.rir);
  note_sample_rate(rir.sample_rate, variant);
  if (args.json) {
    nlohmann::json channels = nlohmann::json::array();
    for (const auto& a : acoustics) {
      channels.push_back({{"t60", a.t60.valid() ? nlohmann::json(a.t60.seconds) : nullptr},
                          {"edt", a.edt.valid() ? nlohmann::json(a.edt.seconds) : nullptr},
                          {"c50", number_or_null(a.c50_db)},
                          {"t60_valid", a.t60.valid()},
                          {"edt_valid", a.edt.valid()}});
    }
    const nlohmann::json out = {
        {"fs", rir.sample_rate}, {"variant", metrics::to_string(variant)}, {"channels", channels}};
    std::printf("%s\n", out.dump(2).c_str());
    return;
  }
  std::printf("%s: %d channel(s), %d Hz, %.3f s; variant %s\n", args.rir.c_str(),
              rir.num_channels(), rir.sample_rate, rir.duration_s(),
              variant_summary(variant).c_str());
  std::printf("%7s  %-20s  %-20s  %s\n", "channel", "T60 (s)", "EDT (s)", "C50 (dB)");
  for (size_t c = 0; c < acoustics.size(); ++c) {
    std::printf("%7zu  %-20s  %-20s  %s\n", c, format_decay(acoustics[c].t60).c_str(),
                format_decay(acoustics[c].edt).c_str(),
                format_value(acoustics[c].c50_db, "%.6f").c_str());
  }
}

// The errors need one STFT window of the ground truth (the STFT error has no frame without it)
// and energy after C50's 50 ms split (C50 is +inf on both sides without it): shorter, every
// such error printed "nan", even for two identical files.
void require_scorable_length(const io::AudioBuffer& gt, const std::string& name,
                             metrics::Variant variant) {
  const int64_t window = metrics::stft_params(variant).n_fft;
  const int64_t split = metrics::c50_split_sample(gt.sample_rate);
  const int64_t needed = std::max(window, split + 1);
  if (gt.num_frames() >= needed) return;
  throw Error(name + ": " + std::to_string(gt.num_frames()) +
              " samples is too short to score: the " + metrics::to_string(variant) +
              " STFT error needs a " + std::to_string(window) +
              "-sample window and C50 energy after 50 ms (sample " + std::to_string(split) +
              " at " + std::to_string(gt.sample_rate) + " Hz); give the whole impulse response, " +
              "at least " + std::to_string(needed) + " samples");
}

void run_compare(const MetricsArgs& args, metrics::Variant variant) {
  const io::AudioBuffer pred = io::read_audio(args.pred);
  const io::AudioBuffer gt = io::read_audio(args.gt);
  require_scorable_length(gt, args.gt, variant);
  const metrics::RirErrors e = metrics::compare_rirs(pred, gt, variant, args.pred, args.gt);
  note_sample_rate(gt.sample_rate, variant);
  if (pred.num_frames() > gt.num_frames()) {
    warn(args.pred + " is longer than " + args.gt + "; its end was cut to the ground truth's " +
         std::to_string(gt.num_frames()) + " samples");
  }
  if (args.json) {
    const nlohmann::json out = {{"t60_error_pct", number_or_null(e.t60_error_pct)},
                                {"c50_error_db", number_or_null(e.c50_error_db)},
                                {"edt_error_s", number_or_null(e.edt_error_s)},
                                {"stft_error", number_or_null(e.stft_error)},
                                {"invalid_t60", e.invalid_t60}};
    std::printf("%s\n", out.dump(2).c_str());
    return;
  }
  std::printf("prediction %s vs ground truth %s: %d channel(s), %d Hz; variant %s\n",
              args.pred.c_str(), args.gt.c_str(), gt.num_channels(), gt.sample_rate,
              variant_summary(variant).c_str());
  std::printf("T60 error   %s %%%s\n", format_value(e.t60_error_pct, "%.4f").c_str(),
              e.invalid_t60 ? "  (invalid: a T60 could not be measured; scored 100 %)" : "");
  std::printf("C50 error   %s dB\n", format_value(e.c50_error_db, "%.6f").c_str());
  std::printf("EDT error   %s s\n", format_value(e.edt_error_s, "%.6f").c_str());
  std::printf("STFT error  %s (mean |log(|STFT|+1e-3) difference|)\n",
              format_value(e.stft_error, "%.6f").c_str());
}

}  // namespace

void register_metrics(CLI::App& app) {
  auto args = std::make_shared<MetricsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "metrics",
      "Room-acoustic metrics of an impulse response (T60, EDT, C50), or the errors of a predicted "
      "RIR against the ground truth, computed exactly as the published NeRAF evaluation.");
  cmd->footer(
      "Variants (only T60 and the STFT error depend on them):\n"
      "  soundspaces  T60 on the full band with a 30 dB decay (pyroomacoustics 0.7.3 "
      "measure_rt60);\n"
      "               STFT n_fft 512, window 512, hop 128. The paper evaluates it at 22050 Hz.\n"
      "  raf          T60 after a 200 Hz biquad high-pass (Q 0.707, output clamped to [-1, 1]) "
      "with\n"
      "               a 10 dB decay; STFT n_fft 1024, window 512, hop 256. Paper: 48000 Hz.\n"
      "EDT = 6 x time to -10 dB on the Schroeder curve (s); C50 splits the energy at\n"
      "int(0.05*fs + 1) samples from sample 0 (dB). Files are measured at their own sample rate.\n"
      "Errors (--pred/--gt): T60 = mean over channels of |pred - gt| / |gt| in percent, 100 % and\n"
      "invalid when any channel's T60 cannot be measured; C50 (dB) and EDT (s) = mean absolute\n"
      "difference; STFT error = mean |log(|STFT(pred)|+1e-3) - log(|STFT(gt)|+1e-3)| over\n"
      "len(gt)/hop frames (the paper reports it for raf only). A shorter prediction is "
      "zero-padded\n"
      "at the end to the ground truth's length; a ground truth shorter than one STFT window or\n"
      "than 50 ms + 1 sample is refused. Values that cannot be measured print as\n"
      "'invalid'/'nan'/'inf' and as null in JSON.\n"
      "Examples:\n"
      "  neraf metrics --rir assets/real/brir_clap.wav\n"
      "  neraf metrics --pred predicted.wav --gt measured.wav --variant raf --json");

  CLI::Option* rir = cmd->add_option("--rir", args->rir,
                                     "Impulse response file (WAV/FLAC, any channel count): print "
                                     "each channel's T60, EDT and C50");
  CLI::Option* pred = cmd->add_option(
      "--pred", args->pred, "Predicted impulse response file; needs --gt. Prints the errors");
  CLI::Option* gt = cmd->add_option(
      "--gt", args->gt,
      "Ground-truth impulse response file; needs --pred (same channel count and sample rate)");
  rir->excludes(pred)->excludes(gt);
  pred->needs(gt);
  gt->needs(pred);
  cmd->add_option("--variant", args->variant,
                  "Evaluation recipe: soundspaces (default; full-band T60, 30 dB decay) or raf "
                  "(200 Hz high-passed T60, 10 dB decay); see below")
      ->check(CLI::IsMember({"soundspaces", "raf"}))
      ->capture_default_str();
  cmd->add_flag(
      "--json", args->json,
      "Print JSON instead of a table: {fs, variant, channels: [{t60, edt, c50, t60_valid, "
      "edt_valid}]} for --rir; {t60_error_pct, c50_error_db, edt_error_s, stft_error, "
      "invalid_t60} for --pred/--gt");

  cmd->callback([args]() {
    if (args->rir.empty() && args->pred.empty()) {
      throw CLI::ValidationError("--rir/--pred/--gt",
                                 "give --rir FILE, or --pred FILE together with --gt FILE");
    }
    const metrics::Variant variant = metrics::parse_variant(args->variant);
    if (!args->rir.empty()) {
      run_single(*args, variant);
    } else {
      run_compare(*args, variant);
    }
  });
}

}  // namespace neraf::cli
