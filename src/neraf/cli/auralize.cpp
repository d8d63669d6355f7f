// `neraf auralize`: dry audio convolved with a room impulse response, written as a WAV file.
#include "neraf/dsp/auralize.h"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/cli/render_audio.h"
#include "neraf/dsp/resample.h"
#include "neraf/io/audio_file.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::cli {
namespace {

struct AuralizeArgs {
  std::string rir_path;
  FieldArgs field;  // render the RIR from a trained field (--run or --model) instead of --rir
  AudioPoseArgs pose;
  std::string dry_path;
  std::string out_path;
  bool normalize = false;
};

// A linear level in decibels, e.g. "-3.2 dB" (unit "dBFS" for sample peaks).
std::string format_db(float linear, const char* unit = "dBFS") {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%+.1f %s", 20.0 * std::log10(std::max(linear, 1e-12f)), unit);
  return buf;
}

// Reads the dry audio and brings it to `rate` (the RIR's), saying so when it resamples.
io::AudioBuffer load_dry(const std::string& path, int rate) {
  io::AudioBuffer dry = io::read_audio(path);
  if (dry.sample_rate != rate) {
    info("note: resampling " + path + " from " + std::to_string(dry.sample_rate) + " Hz to " +
         std::to_string(rate) + " Hz to match the impulse response");
    try {
      dry = dsp::resample(dry, rate);
    } catch (const Error& e) {
      throw Error("--in " + path + " (resampled to the impulse response's " + std::to_string(rate) +
                  " Hz): " + e.what());
    }
  }
  return dry;
}

// Convolves, normalises (or warns about clipping) and writes atomically. Shared by every way of
// getting an impulse response (a file today; a trained model's prediction later).
void auralize_and_write(const io::AudioBuffer& rir, const std::string& rir_name,
                        const std::string& dry_path, const AuralizeArgs& args) {
  const io::AudioBuffer dry = load_dry(dry_path, rir.sample_rate);
  if (dsp::auralized_channels(rir.num_channels(), dry.num_channels()) == 0) {
    throw Error(dry_path + ": has " + std::to_string(dry.num_channels()) + " channels, which " +
                "cannot be combined with the " + std::to_string(rir.num_channels()) +
                "-channel impulse response " + rir_name +
                "; use mono dry audio, a mono RIR, or equal channel counts");
  }
  if (dsp::peak_abs(rir) == 0.0f)
    warn(rir_name + ": every sample of the impulse response is zero, so the output is silence");
  if (dsp::peak_abs(dry) == 0.0f)
    warn(dry_path + ": every sample is zero, so the output is silence");
  io::AudioBuffer wet = dsp::auralize(rir, dry);

  const float peak = dsp::peak_abs(wet);
  std::string level;
  if (peak == 0.0f) {
    level = "silent (every sample is zero)";
  } else if (args.normalize) {
    const float gain = dsp::normalize_peak(wet, 0.99f);
    level = "peak-normalised to 0.99 (gain " + format_db(gain, "dB") + ")";
  } else {
    level = "peak " + format_db(peak);
    warn_above_full_scale(wet, args.out_path, "pass --normalize");
  }
  io::write_audio(args.out_path, wet);
  std::printf("wrote %s: %d ch, %d Hz, %.2f s, %s\n", args.out_path.c_str(), wet.num_channels(),
              wet.sample_rate, wet.duration_s(), level.c_str());
}

}  // namespace

void register_auralize(CLI::App& app) {
  auto args = std::make_shared<AuralizeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "auralize",
      "Convolve dry (anechoic) audio with a room impulse response: hear the room.\n"
      "Mono dry audio with an N-channel RIR (e.g. binaural) gives N channels; stereo dry audio\n"
      "with a stereo RIR is convolved channel by channel; with a mono RIR every dry channel is\n"
      "convolved. Dry audio at another sample rate is resampled to the RIR's rate. The output\n"
      "has len(dry) + len(rir) - 1 samples and is written as a 32-bit float WAV (.flac: 24-bit\n"
      "FLAC).\n"
      "Give the impulse response as a file (--rir) or as a pose in a trained field (--run or\n"
      "--model with --mic, --src and the orientation): the RIR is then rendered exactly as\n"
      "'neraf render rir'. For a moving listener see 'neraf render trajectory'.");
  cmd->footer("With --run or --model:\n" + audio_pose_help() +
              "Example: neraf auralize --run runs/demo --mic 2.0,1.5,1.6 --src 1.1,1.2,0.9 "
              "--yaw 90 --in speech.wav --out speech_in_room.wav --normalize");
  CLI::Option* rir_opt = cmd->add_option(
      "--rir", args->rir_path,
      "Room impulse response to convolve with: WAV/FLAC, mono or multichannel, e.g. a measured "
      "RIR or one rendered by 'neraf render rir' (this or --run)");
  add_field_options(cmd, args->field, true);
  CLI::Option* run_opt = args->field.run_opt;
  CLI::Option* model_opt = args->field.model_opt;
  rir_opt->excludes(run_opt)->excludes(model_opt);
  const auto pose_opts = add_audio_pose_options(cmd, args->pose, true, false);
  cmd->add_option(
         "--in", args->dry_path,
         "Dry audio to place in the room (WAV/FLAC, mono, stereo, or as many channels as the RIR)")
      ->required();
  cmd->add_option("--out", args->out_path, "Output file (written atomically)")->required();
  cmd->add_flag("--normalize", args->normalize,
                "Scale the result so its peak is 0.99 (same gain on all channels). Without it the "
                "level is kept and a warning is printed if the result would clip");
  cmd->callback([cmd, args, rir_opt, run_opt, model_opt, pose_opts] {
    // Checked here rather than with ->required(): --rir, --run and --model are alternatives;
    // still usage errors (exit 2).
    const bool field = run_opt->count() > 0 || model_opt->count() > 0;
    if (rir_opt->count() == 0 && !field) throw CLI::RequiredError("--rir, --run or --model");
    require_safe_output(
        {"--out", args->out_path},
        {{"--in", args->dry_path}, {"--rir", args->rir_path}, {"--model", args->field.model}},
        args->field.run);
    if (field) {
      if (pose_opts.first->count() == 0) throw CLI::RequiredError("--mic (with --run/--model)");
      if (pose_opts.second->count() == 0) throw CLI::RequiredError("--src (with --run/--model)");
      const LoadedField loaded = load_field(args->field);
      std::string summary;
      const io::AudioBuffer rir = render_rir_from_field(loaded, args->field, args->pose, &summary);
      info("rendered the RIR: " + summary);
      auralize_and_write(rir, "rendered from " + loaded.name, args->dry_path, *args);
      return;
    }
    if (pose_opts.first->count() + pose_opts.second->count() + args->pose.yaw_opt->count() +
            args->pose.src_yaw_opt->count() >
        0)
      throw CLI::ValidationError(
          "--mic/--src/--yaw/--src-yaw: only with --run or --model (a field to render); a --rir "
          "file is used as it is");
    for (const char* flag : {"--seed", "--allow-outside"})
      if (cmd->count(flag) > 0)
        throw CLI::ValidationError(std::string(flag) +
                                   ": only with --run or --model (it sets how a field's RIR is "
                                   "rendered); a --rir file is used as it is, so drop it");
    const io::AudioBuffer rir = io::read_audio(args->rir_path);
    auralize_and_write(rir, args->rir_path, args->dry_path, *args);
  });
}

}  // namespace neraf::cli
