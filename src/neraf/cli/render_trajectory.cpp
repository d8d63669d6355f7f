// `neraf render trajectory`: dry audio heard by a listener moving along a timed path, auralized
// through neraf_rt's streaming convolver (uniformly partitioned overlap-save, a crossfade per RIR
// change), the RIR re-predicted at a fixed pose-update rate; optionally a rendered view per video
// frame. Registered by add_render_audio_commands (render_audio.cpp).
#include <torch/torch.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "neraf/cli/flag_checks.h"
#include "neraf/cli/render_audio.h"
#include "neraf/dsp/auralize.h"
#include "neraf/dsp/resample.h"
#include "neraf/geometry/trajectory.h"
#include "neraf/infer/run.h"
#include "neraf/io/atomic_file.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/neraf_rt.h"
#include "neraf/render/view.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;

namespace neraf::cli {
namespace {

struct TrajectoryArgs {
  FieldArgs field;
  std::string path;
  std::string dry;
  std::string out;
  double rate_hz = 20;  // pose updates per second
  int block = 256;
  std::string frames_dir;
  double fps = 10;
  uint64_t seed = 0;
  bool normalize = false;
};

// The dry signal as the stream takes it: mono (channels averaged) at `rate`.
std::vector<float> mono_dry(const std::string& path, int rate) {
  io::AudioBuffer dry = io::read_audio(path);
  if (dry.sample_rate != rate) {
    info("note: resampling " + path + " from " + std::to_string(dry.sample_rate) + " Hz to " +
         std::to_string(rate) + " Hz to match the field");
    try {
      dry = dsp::resample(dry, rate);
    } catch (const Error& e) {
      throw Error("--in " + path + ": " + e.what());
    }
  }
  if (dry.num_channels() > 1)
    info("note: " + path + " has " + std::to_string(dry.num_channels()) +
         " channels; the listener hears their average (a mono source)");
  std::vector<float> mono(static_cast<size_t>(dry.num_frames()), 0.0f);
  for (const auto& ch : dry.channels)
    for (size_t i = 0; i < mono.size(); ++i) mono[i] += ch[i] / dry.num_channels();
  if (std::all_of(mono.begin(), mono.end(), [](float v) { return v == 0.0f; }))
    warn(path + ": every sample is zero (or the channels cancel), so the output is silence");
  return mono;
}

bool same_pose(const geometry::TimedPose& a, const geometry::TimedPose& b) {
  auto same = [](const geometry::Vec3& u, const geometry::Vec3& v) {
    return u.x == v.x && u.y == v.y && u.z == v.z;
  };
  return same(a.mic, b.mic) && same(a.source, b.source) && a.yaw_deg == b.yaw_deg;
}

void check_stream(neraf_status status, const std::string& what) {
  if (status != NERAF_OK) throw Error(what + ": " + neraf_last_error());
}

// The radiance field --frames renders: the run's own, or an audio run's vision run.
infer::LoadedRun load_view_run(const FieldArgs& field_args) {
  const std::string config = (fs::path(field_args.run) / "config.json").string();
  const infer::TrainConfig cfg = infer::read_run_config(config);
  const bool own = cfg.modality != infer::Modality::audio;
  require(own || !cfg.audio.vision_run.empty(),
          field_args.run +
              ": has no radiance field for --frames (an audio-only run without "
              "--vision-run)");
  std::error_code ec;
  require(own || fs::is_directory(cfg.audio.vision_run, ec),
          config + ": audio.vision_run " + cfg.audio.vision_run +
              " (the radiance field --frames renders) is gone; restore it or drop --frames");
  return infer::load_run(own ? field_args.run : cfg.audio.vision_run, torch::kCPU,
                         own ? field_args.checkpoint : "");
}

// The path sampled `rate` times a second; a refused rate names `flag`, the one that set it.
std::vector<geometry::TimedPose> sample_for(const geometry::Trajectory& path, double rate,
                                            double duration_s, const std::string& flag) {
  try {
    return geometry::sample_trajectory(path, rate, duration_s);
  } catch (const Error& e) {
    throw Error(flag + ": " + e.what());
  }
}

// One PNG per video frame (`poses`, sampled at --fps) into `dir`: the radiance field seen from
// the listener, facing its heading.
void render_frames(infer::LoadedRun& run, const std::vector<geometry::TimedPose>& poses,
                   const std::string& dir) {
  Progress progress("render frames", static_cast<int64_t>(poses.size()),
                    ProgressOptions{"frame", 0.2, 10.0, true});
  for (size_t i = 0; i < poses.size(); ++i) {
    const render::Camera cam = render::dataset_camera(
        render::listener_camera_to_world(poses[i].mic, poses[i].yaw_deg), run.manifest);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.png", i);
    render::render_view(run, cam, (fs::path(dir) / name).string(), "",
                        run.config.eval_rays_per_chunk);
    progress.update(static_cast<int64_t>(i) + 1);
  }
  progress.finish();
}

void run_trajectory(const TrajectoryArgs& args) {
  require(args.frames_dir.empty() || !args.field.run.empty(),
          "--frames: needs --run (a run with a radiance field); an exported model holds only "
          "the acoustic field");
  const geometry::Trajectory path = geometry::load_trajectory(args.path);
  const LoadedField field = load_field(args.field);
  // Loaded before the audio is rendered, so a missing radiance field leaves nothing written.
  std::optional<infer::LoadedRun> view_run;
  if (!args.frames_dir.empty()) view_run = load_view_run(args.field);
  const infer::AudioRunInfo& info = field.field->info();
  const int sr = info.sample_rate;
  const std::vector<float> dry = mono_dry(args.dry, sr);

  const size_t rir_length = static_cast<size_t>(info.stft.hop_length * (info.max_len - 1));
  const size_t out_length = dry.size() + rir_length - 1;
  const double duration_s = static_cast<double>(out_length) / sr;
  if (path.keyframes.front().time >= duration_s) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  ": its first keyframe is at %.3f s, after the audio ends (%.3f s), so the whole "
                  "render stays at that first pose",
                  path.keyframes.front().time, duration_s);
    warn(args.path + msg);
  }
  // The poses of the updates; the path holds its last pose after its end.
  const std::vector<geometry::TimedPose> updates =
      sample_for(path, args.rate_hz, duration_s, "--rate");
  // Checked before the audio work, which takes longer than this.
  const std::vector<geometry::TimedPose> frames =
      view_run ? sample_for(path, args.fps, path.duration(), "--fps")
               : std::vector<geometry::TimedPose>();
  for (const geometry::TimedPose& p : updates) {
    char where[96];
    std::snprintf(where, sizeof where, "%s at t = %.3f s:", args.path.c_str(), p.time);
    check_inside(p.mic, std::string(where) + " mic", info.aabb, args.field.allow_outside);
    check_inside(p.source, std::string(where) + " source", info.aabb, args.field.allow_outside);
  }

  neraf_stream* raw = nullptr;
  check_stream(neraf_stream_create(nullptr, info.channels, args.block, rir_length, &raw),
               "--block " + std::to_string(args.block));
  std::unique_ptr<neraf_stream, void (*)(neraf_stream*)> stream(raw, neraf_stream_free);

  const size_t block = static_cast<size_t>(args.block);
  const size_t n_blocks = (out_length + block - 1) / block;
  std::vector<std::vector<float>> wet(static_cast<size_t>(info.channels),
                                      std::vector<float>(n_blocks * block, 0.0f));
  std::vector<float> in(block), out(block * static_cast<size_t>(info.channels)), planar;
  size_t next_update = 0;
  int64_t rirs = 0;
  geometry::TimedPose last;  // the pose of the RIR in use (a standing listener needs no new one)
  Progress progress("render trajectory", static_cast<int64_t>(n_blocks),
                    ProgressOptions{"block", 0.2, 10.0, true});
  for (size_t b = 0; b < n_blocks; ++b) {
    const double t = static_cast<double>(b * block) / sr;
    // The latest update due by this block's start (updates between two blocks collapse).
    bool due = false;
    while (next_update < updates.size() && updates[next_update].time <= t + 1e-12) {
      ++next_update;
      due = true;
    }
    const geometry::TimedPose* p = due ? &updates[next_update - 1] : nullptr;
    if (p && (rirs == 0 || !same_pose(*p, last))) {
      last = *p;
      const auto rir = field.field->predict_waveform(p->mic, p->source, p->yaw_deg, args.seed,
                                                     static_cast<int64_t>(rir_length));  // [C][L]
      planar.clear();
      for (const auto& ch : rir) planar.insert(planar.end(), ch.begin(), ch.end());
      check_stream(neraf_stream_set_rir(stream.get(), planar.data(), info.channels, rir_length),
                   "the predicted RIR");
      // Offline: wait for the worker, so the output does not depend on timing.
      check_stream(neraf_stream_wait(stream.get(), 60000), "the streaming convolver");
      ++rirs;
    }
    for (size_t i = 0; i < block; ++i) {
      const size_t k = b * block + i;
      in[i] = k < dry.size() ? dry[k] : 0.0f;
    }
    check_stream(neraf_stream_process(stream.get(), in.data(), out.data()),
                 "the streaming convolver");
    for (size_t c = 0; c < wet.size(); ++c)
      std::copy(out.begin() + c * block, out.begin() + (c + 1) * block, wet[c].begin() + b * block);
    progress.update(static_cast<int64_t>(b) + 1);
  }
  progress.finish();

  io::AudioBuffer result;
  result.sample_rate = sr;
  result.channels = std::move(wet);
  for (auto& ch : result.channels) ch.resize(out_length);
  if (args.normalize) {
    dsp::normalize_peak(result, 0.99f);
  } else {
    warn_above_full_scale(result, args.out, "pass --normalize");
  }
  if (view_run) {
    // The frames first: a failure there leaves neither the frames nor the WAV.
    io::write_folder_atomically(
        args.frames_dir, [&](const std::string& tmp) { render_frames(*view_run, frames, tmp); });
    std::printf("wrote %s: frames at %.3g fps\n", args.frames_dir.c_str(), args.fps);
  }
  io::write_audio(args.out, result);
  std::printf(
      "wrote %s: %d ch, %d Hz, %.2f s; %lld RIRs from %s (step %lld) along %s (%.2f s, pose "
      "updates at %.3g Hz, %d-sample blocks)\n",
      args.out.c_str(), result.num_channels(), sr, result.duration_s(),
      static_cast<long long>(rirs), field.name.c_str(), static_cast<long long>(field.step),
      args.path.c_str(), path.duration(), args.rate_hz, args.block);
}

}  // namespace

void add_render_trajectory(CLI::App& render) {
  auto args = std::make_shared<TrajectoryArgs>();
  CLI::App* cmd = render.add_subcommand(
      "trajectory",
      "Auralize dry audio for a listener (and optionally a source) moving along a timed path, "
      "through the streaming convolver, the RIR re-predicted at --rate poses per second; with "
      "--frames also a rendered view per video frame");
  cmd->footer(
      "The path (docs/PATH_FORMAT.md): JSON keyframes of time (s), mic position, yaw (and\n"
      "optionally the source per keyframe), interpolated linearly (yaw along the shorter arc);\n"
      "after the last keyframe the listener stays there. The yaw is the orientation the model\n"
      "takes (the receiver heading for SoundSpaces runs, the source yaw for RAF runs).\n"
      "At every pose update (--rate per second, at the next block boundary) the field's RIR is\n"
      "predicted (Griffin-Lim, --seed) and handed to neraf_rt's streaming convolver, which\n"
      "crossfades to it over one block. The dry audio is resampled to the field's rate and\n"
      "mixed to mono; the output has len(dry) + len(rir) - 1 samples, one channel per RIR\n"
      "channel (binaural for SoundSpaces runs), 32-bit float WAV.\n"
      "--frames DIR (with --run of a run that has a radiance field): frame_00000.png, ... at\n"
      "--fps, the camera at the listener's position looking along its heading (0 deg: -z,\n"
      "90 deg: -x), with the run's training camera intrinsics.\n"
      "Example: neraf render trajectory --model demo.nrf --path examples/paths/demo_walk.json "
      "--in speech.wav --out walk.wav");
  add_field_options(cmd, args->field, true);
  cmd->add_option("--path", args->path, "Timed path (JSON, docs/PATH_FORMAT.md)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--in", args->dry, "Dry (anechoic) audio, WAV/FLAC")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "Output WAV (written atomically)")->required();
  cmd->add_option("--rate", args->rate_hz, "Pose updates per second (a new RIR each)")
      ->check(real_number(0.01, geometry::kMaxSampleRateHz))
      ->capture_default_str();
  cmd->add_option("--block", args->block,
                  "Samples per block of the streaming convolver (16 to 16384)")
      ->transform(whole_number(16, 16384))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Seed of Griffin-Lim's random initial phases")
      ->transform(seed_number())
      ->capture_default_str();
  cmd->add_flag("--normalize", args->normalize, "Scale the result so its peak is 0.99");
  cmd->add_option("--frames", args->frames_dir,
                  "Also render a view per video frame (frame_00000.png, ...) into this new or "
                  "empty folder (needs --run with a radiance field)");
  cmd->add_option("--fps", args->fps, "Video frames per second for --frames")
      ->check(real_number(0.01, 120))
      ->capture_default_str();
  cmd->callback([args] {
    require_safe_output({"--out", args->out}, {{"--in", args->dry}, {"--model", args->field.model}},
                        args->field.run);
    require_safe_output_folder({"--frames", args->frames_dir},
                               {{"--out", args->out}, {"--in", args->dry}, {"--path", args->path}},
                               args->field.run);
    run_trajectory(*args);
  });
}

}  // namespace neraf::cli
