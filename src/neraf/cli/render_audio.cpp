// `neraf render rir` and `neraf render loudness`: RIRs and loudness maps from a trained run's
// acoustic field (neraf-reference.md §5). Registered by register_render (render.cpp).
#include "neraf/cli/render_audio.h"

#include <torch/torch.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "neraf/cli/flag_checks.h"
#include "neraf/dsp/auralize.h"
#include "neraf/geometry/trajectory.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/exported_model.h"
#include "neraf/io/atomic_file.h"
#include "neraf/render/loudness.h"
#include "neraf/render/rir.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;

namespace neraf::cli {
namespace {

// Metres as a person reads them: 1.50, or 1e+300 (not 300 digits).
std::string metres(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, std::abs(v) < 1e5 ? "%.2f" : "%.3g", v);
  return buf;
}

std::string fmt3(const geometry::Vec3& p) {
  return "(" + metres(p.x) + ", " + metres(p.y) + ", " + metres(p.z) + ")";
}

std::string aabb_text(const data::Aabb& b) {
  return "x " + metres(b.min.x) + ".." + metres(b.max.x) + ", y " + metres(b.min.y) + ".." +
         metres(b.max.y) + ", z " + metres(b.min.z) + ".." + metres(b.max.z);
}

// A usage error (exit 2) naming the flag.
geometry::Vec3 parse_flag_position(const std::string& text, const std::string& flag) {
  try {
    return render::parse_position(text, flag);
  } catch (const Error& e) {
    throw CLI::ValidationError(e.what());
  }
}

render::AudioModelInfo model_info(const infer::AudioRunInfo& i) {
  render::AudioModelInfo m;
  m.layout = i.layout;
  m.sample_rate = i.sample_rate;
  m.stft = i.stft;
  m.channels = i.channels;
  m.max_len = i.max_len;
  m.aabb = i.aabb;
  return m;
}

render::LogStftFn bind(const infer::AudioField& field) {
  return [&field](const torch::Tensor& mic, const torch::Tensor& src, const torch::Tensor& yaw) {
    return field.predict_log_stft_batch(mic, src, yaw);
  };
}

// The orientation the model takes: the receiver heading (SoundSpaces) or the source yaw (RAF).
double resolve_yaw(const AudioPoseArgs& a, data::AudioLayout layout, const std::string& run_dir) {
  const bool yaw = a.yaw_opt && a.yaw_opt->count() > 0;
  const bool src_yaw = a.src_yaw_opt && a.src_yaw_opt->count() > 0;
  if (layout == data::AudioLayout::soundspaces) {
    require(!src_yaw, run_dir +
                          " is a SoundSpaces-layout run: its sources are omnidirectional and the "
                          "model's orientation is the receiver heading; use --yaw, not --src-yaw");
    const double h = std::fmod(std::fmod(a.yaw, 360.0) + 360.0, 360.0);
    if (std::abs(h - 90.0 * std::round(h / 90.0)) > 1e-9) {
      warn("--yaw " + std::to_string(a.yaw) +
           ": SoundSpaces runs are trained on receiver headings 0, 90, 180 and 270 only; other "
           "headings are the network's interpolation");
    }
    return a.yaw;
  }
  require(!yaw, run_dir +
                    " is a RAF-layout run: its microphones are omnidirectional and the model's "
                    "orientation is the source yaw; use --src-yaw, not --yaw");
  return a.src_yaw;
}

struct LoudnessArgs {
  FieldArgs field;
  AudioPoseArgs pose;
  std::string out;
  std::string csv;
  double spacing = 0.1;
  double height = std::numeric_limits<double>::quiet_NaN();
  int threads = 0;
};

// `render rir --poses POSES.json --out DIR`: DIR/<name>.wav per pose and DIR/summary.csv, built
// in a temporary folder beside DIR and renamed into place, so a failure leaves no half-written DIR.
void render_pose_list(const LoadedField& field, const FieldArgs& field_args,
                      const AudioPoseArgs& pose_args, const std::string& poses_path,
                      const std::string& out_dir) {
  const std::vector<geometry::NamedPose> poses = geometry::load_pose_list(poses_path);
  const infer::AudioRunInfo& info = field.field->info();
  for (size_t i = 0; i < poses.size(); ++i) {
    const std::string where =
        poses_path + ": poses[" + std::to_string(i) + "] (" + poses[i].name + ")";
    check_inside(poses[i].mic, where + " mic", info.aabb, field_args.allow_outside);
    check_inside(poses[i].source, where + " source", info.aabb, field_args.allow_outside);
  }
  std::error_code ec;
  require(!fs::exists(out_dir, ec) || (fs::is_directory(out_dir, ec) && fs::is_empty(out_dir, ec)),
          out_dir + ": exists and is not an empty folder; choose a new --out folder or remove it");
  io::write_folder_atomically(out_dir, [&](const std::string& tmp_dir) {
    const fs::path tmp(tmp_dir);
    std::string csv =
        "name,file,mic_x,mic_y,mic_z,src_x,src_y,src_z,yaw_deg,channels,"
        "sample_rate,duration_s,peak\n";
    render::RirRenderOptions o;
    o.seed = pose_args.seed;
    Progress progress("render rir", static_cast<int64_t>(poses.size()),
                      ProgressOptions{"RIR", 0.2, 10.0, true});
    for (size_t i = 0; i < poses.size(); ++i) {
      const geometry::NamedPose& p = poses[i];
      const io::AudioBuffer rir =
          render::render_rir(bind(*field.field), model_info(info), p.mic, p.source, p.yaw_deg, o);
      const std::string file = p.name + ".wav";
      io::write_audio((tmp / file).string(), rir);
      const float peak = dsp::peak_abs(rir);
      char row[512];
      std::snprintf(row, sizeof row, "%s,%s,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%.6g,%.6g\n",
                    p.name.c_str(), file.c_str(), p.mic.x, p.mic.y, p.mic.z, p.source.x, p.source.y,
                    p.source.z, p.yaw_deg, rir.num_channels(), rir.sample_rate, rir.duration_s(),
                    peak);
      csv += row;
      progress.update(static_cast<int64_t>(i) + 1);
    }
    progress.finish();
    io::write_text_atomically((tmp / "summary.csv").string(), csv);
  });
  std::printf("wrote %s: %zu RIRs (%s, step %lld) and summary.csv\n", out_dir.c_str(), poses.size(),
              field.name.c_str(), static_cast<long long>(field.step));
}

void add_render_rir(CLI::App& render) {
  struct Args {
    FieldArgs field;
    AudioPoseArgs pose;
    std::string poses;
    std::string out;
    int threads = 0;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = render.add_subcommand(
      "rir",
      "Render the room impulse response of a trained acoustic field at a pose (WAV), or at "
      "every pose of a list (--poses: one WAV each and a summary CSV)");
  cmd->footer(
      audio_pose_help() +
      "\nThe predicted log-magnitude STFT becomes clip(exp(x) - 1e-3, 0, 1e4) and a waveform "
      "by\nGriffin-Lim (32 iterations, momentum 0.99, random phases from --seed), written "
      "as a\n32-bit float WAV at the run's sample rate (22050 Hz SoundSpaces, 2 channels "
      "binaural;\n48000 Hz RAF, mono), hop*(T-1) samples long.\n"
      "--poses FILE: the pose list format of docs/PATH_FORMAT.md; --out is then a new folder\n"
      "that receives <name>.wav per pose and summary.csv (name, file, mic, source, yaw,\n"
      "channels, sample rate, duration, peak).\n"
      "Examples:\n  neraf render rir --run runs/demo --mic 2.0,1.5,1.6 --src 1.1,1.2,0.9 "
      "--yaw 90 --out rir.wav\n  neraf render rir --model demo.nrf --poses "
      "examples/paths/demo_poses.json --out rirs/");
  add_field_options(cmd, args->field, true);
  const auto pose_opts = add_audio_pose_options(cmd, args->pose, true, false);
  CLI::Option* poses_opt = cmd->add_option(
      "--poses", args->poses, "A pose list (JSON, docs/PATH_FORMAT.md): render every pose");
  poses_opt->excludes(pose_opts.first)->excludes(pose_opts.second);
  poses_opt->excludes(args->pose.yaw_opt)->excludes(args->pose.src_yaw_opt);
  cmd->add_option("--out", args->out, "Output WAV (written atomically); with --poses a new folder")
      ->required();
  cmd->add_option("--threads", args->threads,
                  "CPU threads (default: all cores; at most 4 x the cores)")
      ->transform(thread_count());
  cmd->callback([args, pose_opts, poses_opt] {
    if (args->threads > 0) torch::set_num_threads(args->threads);
    if (poses_opt->count() == 0) {
      if (pose_opts.first->count() == 0) throw CLI::RequiredError("--mic (or --poses)");
      if (pose_opts.second->count() == 0) throw CLI::RequiredError("--src (or --poses)");
    }
    if (poses_opt->count() == 0)
      require_safe_output({"--out", args->out}, {{"--model", args->field.model}}, args->field.run);
    else
      require_safe_output_folder({"--out", args->out},
                                 {{"--model", args->field.model}, {"--poses", args->poses}},
                                 args->field.run);
    const LoadedField field = load_field(args->field);
    if (poses_opt->count() > 0) {
      render_pose_list(field, args->field, args->pose, args->poses, args->out);
      return;
    }
    std::string summary;
    const io::AudioBuffer rir = render_rir_from_field(field, args->field, args->pose, &summary);
    warn_above_full_scale(rir, args->out, "");
    io::write_audio(args->out, rir);
    std::printf("wrote %s: %d ch, %d Hz, %.3f s; %s\n", args->out.c_str(), rir.num_channels(),
                rir.sample_rate, rir.duration_s(), summary.c_str());
  });
}

void add_render_loudness(CLI::App& render) {
  auto args = std::make_shared<LoudnessArgs>();
  CLI::App* cmd = render.add_subcommand(
      "loudness", "Render a loudness map over the floor for one source (PNG heat map + CSV)");
  cmd->footer(
      audio_pose_help() +
      "\nThe map, as the paper's figure (reference viz/loudness_maps): microphones on a grid\n"
      "over the train microphones' bounding box widened by 0.5 m (x, z), all at --height;\n"
      "per position loudness = log(sum over frames of the RMS of channel 0 of\n"
      "clip(exp(stft) - 1e-3, 0, 1e4)) (librosa.feature.rms on the spectrogram, frame_length\n"
      "n_fft; channel 0 = the left ear for binaural runs). The PNG is a top view: x to the\n"
      "right, z downwards, viridis from the quietest (dark) to the loudest (yellow) position,\n"
      "the source as a white ring; the colour bar shows the log-loudness range. The raw values\n"
      "go to a CSV (x_m,y_m,z_m,log_loudness). For SoundSpaces runs --yaw is the heading of\n"
      "every microphone of the grid.\n"
      "Example: neraf render loudness --run runs/demo --src 1.1,1.2,0.9 --out loudness.png\n"
      "  (--model demo.nrf instead of --run: the exported model of neraf export)");
  add_field_options(cmd, args->field, true);
  add_audio_pose_options(cmd, args->pose, false);
  cmd->add_option("--out", args->out, "Output PNG (written atomically)")->required();
  cmd->add_option("--csv", args->csv, "Where to write the values (default: --out with .csv)");
  cmd->add_option("--spacing", args->spacing,
                  "Grid spacing in metres (default 0.1, as the reference; made coarser "
                  "automatically when the grid would exceed 2500 positions)")
      ->check(real_number(0.001, 100));
  cmd->add_option("--height", args->height,
                  "Microphone height y in metres (default: the middle of the train microphones' "
                  "heights, i.e. their height when they share one)")
      ->check(real_number(-10000, 10000));
  cmd->add_option("--threads", args->threads,
                  "CPU threads (default: all cores; at most 4 x the cores)")
      ->transform(thread_count());
  cmd->callback([args] {
    if (args->threads > 0) torch::set_num_threads(args->threads);
    const geometry::Vec3 src = parse_flag_position(args->pose.src, "--src");
    require_safe_output({"--out", args->out},
                        {{"--csv", args->csv}, {"--model", args->field.model}}, args->field.run);
    require_safe_output({"--csv", args->csv}, {{"--model", args->field.model}}, args->field.run);
    require_extension({"--out", args->out}, ".png");
    if (!args->csv.empty()) require_extension({"--csv", args->csv}, ".csv");
    const LoadedField field = load_field(args->field);
    const infer::AudioRunInfo& info = field.field->info();
    const double yaw = resolve_yaw(args->pose, info.layout, field.name);
    check_inside(src, "--src", info.aabb, args->field.allow_outside);
    render::FloorGridOptions go;
    go.spacing_m = args->spacing;
    go.height_m = args->height;
    go.max_points = 2500;
    const render::FloorGrid grid = render::make_floor_grid(info.aabb, go);
    if (grid.spacing > args->spacing * 1.0001) {
      neraf::info("note: grid spacing raised to " + std::to_string(grid.spacing).substr(0, 5) +
                  " m to keep the map under " + std::to_string(go.max_points) + " positions");
    }
    const auto t0 = std::chrono::steady_clock::now();
    const render::LoudnessMap map =
        render::compute_loudness_map(bind(*field.field), grid, src, yaw, 64, true);
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string csv = args->csv.empty() ? render::csv_path_for(args->out) : args->csv;
    render::write_loudness_png(args->out, map);
    render::write_loudness_csv(csv, map);
    const torch::Tensor v = map.values;
    std::printf(
        "wrote %s and %s: %zu x %zu positions (x %.2f..%.2f, z %.2f..%.2f, y %.2f m, spacing "
        "%.2f m), log loudness %.3f..%.3f, %.1f s (step %lld)\n",
        args->out.c_str(), csv.c_str(), grid.x.size(), grid.z.size(), grid.x.front(), grid.x.back(),
        grid.z.front(), grid.z.back(), grid.height, grid.spacing, v.min().item<double>(),
        v.max().item<double>(), secs, static_cast<long long>(field.step));
  });
}

}  // namespace

std::string audio_pose_help() {
  return "Poses are in the DATASET's frame, metres, y UP, exactly as NeRAF uses them:\n"
         "  SoundSpaces: a metadata/points.txt row 'i x y z' is the point X,Y,Z = x,z,-y (no\n"
         "    height offset); for scenes made by 'neraf synth' this is the scene.json frame.\n"
         "  RAF: as written in rx_pos.txt / tx_pos.txt.\n"
         "Orientation (one angle in degrees, what the model was trained on):\n"
         "  SoundSpaces runs: --yaw = the receiver (listener) heading, the binaural_rirs/<angle>/\n"
         "    folder angle (trained: 0, 90, 180, 270); a rotation about +y, heading 0 faces -z,\n"
         "    90 faces -x (Habitat). --src-yaw is an error (omnidirectional sources).\n"
         "  RAF runs: --src-yaw = the source yaw about +y (tx_pos.txt quaternion, as_euler('yxz')\n"
         "    [0]); --yaw is an error (omnidirectional microphones).\n"
         "Positions outside the field's training box (train microphones +- 1 m) are an error:\n"
         "NeRAF replaces such a position by zeros, so the prediction would not describe it;\n"
         "--allow-outside renders anyway (with a warning).\n";
}

std::pair<CLI::Option*, CLI::Option*> add_audio_pose_options(CLI::App* cmd, AudioPoseArgs& a,
                                                             bool with_mic, bool required,
                                                             CLI::Option* needs) {
  // Headings in either sense of rotation; beyond one turn is a typo, not a heading.
  const CLI::Validator degrees = real_number(-360, 360);
  std::vector<CLI::Option*> opts;
  CLI::Option* mic = nullptr;
  if (with_mic) {
    mic = cmd->add_option("--mic", a.mic, "Microphone (receiver) position X,Y,Z in metres");
    opts.push_back(mic);
  }
  CLI::Option* src = cmd->add_option("--src", a.src, "Sound source position X,Y,Z in metres");
  opts.push_back(src);
  a.yaw_opt =
      cmd->add_option("--yaw", a.yaw, "Receiver heading in degrees (SoundSpaces runs; default 0)")
          ->check(degrees);
  a.src_yaw_opt =
      cmd->add_option("--src-yaw", a.src_yaw, "Source yaw in degrees (RAF runs; default 0)")
          ->check(degrees);
  opts.push_back(a.yaw_opt);
  opts.push_back(a.src_yaw_opt);
  if (with_mic) {  // an RIR is rendered: Griffin-Lim needs a seed
    opts.push_back(
        cmd->add_option("--seed", a.seed, "Seed of Griffin-Lim's random initial phases (default 0)")
            ->transform(seed_number()));
  }
  for (CLI::Option* o : opts) {
    if (required && (o == mic || o == src)) o->required();
    if (needs) o->needs(needs);
  }
  return {mic, src};
}

void add_field_options(CLI::App* cmd, FieldArgs& a, bool poses) {
  a.run_opt = cmd->add_option("--run", a.run, "Run folder made by neraf train (joint or audio)");
  a.model_opt = cmd->add_option("--model", a.model,
                                "Exported model file made by neraf export (instead of --run)");
  a.run_opt->excludes(a.model_opt);
  cmd->add_option("--checkpoint", a.checkpoint,
                  "A specific checkpoint file of --run (default: the run's latest)")
      ->needs(a.run_opt);
  cmd->add_option("--precision", a.precision,
                  "Arithmetic of --run's acoustic field: fp32 (default, whatever trained the run) "
                  "or bf16 (as a bf16 run trained)")
      ->check(CLI::IsMember({"fp32", "bf16"}))
      ->needs(a.run_opt);
  cmd->add_option("--scene", a.scene,
                  "The scene of a multi-scene --run (neraf train with several --data): its name "
                  "(the dataset folder's) or index")
      ->needs(a.run_opt);
  if (poses) {
    cmd->add_flag("--allow-outside", a.allow_outside,
                  "Render poses outside the field's training box (train microphones +- 1 m) "
                  "with a warning instead of an error");
  }
}

LoadedField load_field(const FieldArgs& a) {
  LoadedField out;
  if (!a.model.empty()) {
    auto model = std::make_unique<infer::ExportedModel>(infer::load_exported_model(a.model));
    model->allow_outside(true);  // the commands check the poses themselves (check_inside)
    out.step = model->metadata().value("step", int64_t{0});
    out.name = a.model;
    out.field = std::move(model);
    return out;
  }
  if (a.run.empty()) throw CLI::RequiredError("--run or --model");
  auto run = std::make_unique<infer::AudioRun>(infer::load_audio_run(
      a.run, torch::kCPU, a.checkpoint, nerf::parse_precision(a.precision, "--precision"),
      /*calibrated=*/true, infer::scene_flag(a.run, a.scene)));
  out.step = run->step();
  out.name = a.run;
  out.field = std::move(run);
  return out;
}

void check_inside(const geometry::Vec3& p, const std::string& what, const data::Aabb& box,
                  bool allow_outside) {
  if (render::inside_open_box(p, box)) return;
  const std::string text = what + " " + fmt3(p) + " is outside the field's training box (" +
                           aabb_text(box) +
                           ", the train microphones +- 1 m, open: a position on a face counts "
                           "as outside); NeRAF replaces such a position by zeros, so the "
                           "prediction would not describe it";
  require(allow_outside, text + "; choose a position inside, or pass --allow-outside");
  warn(text);
}

io::AudioBuffer render_rir_from_field(const LoadedField& field, const FieldArgs& field_args,
                                      const AudioPoseArgs& args, std::string* summary) {
  const geometry::Vec3 mic = parse_flag_position(args.mic, "--mic");
  const geometry::Vec3 src = parse_flag_position(args.src, "--src");
  const infer::AudioRunInfo& info = field.field->info();
  const double yaw = resolve_yaw(args, info.layout, field.name);
  check_inside(mic, "--mic", info.aabb, field_args.allow_outside);
  check_inside(src, "--src", info.aabb, field_args.allow_outside);
  render::RirRenderOptions o;
  o.seed = args.seed;
  const io::AudioBuffer rir =
      render::render_rir(bind(*field.field), model_info(info), mic, src, yaw, o);
  if (summary) {
    *summary = std::string(data::to_string(info.layout)) + " field " + field.name + ", step " +
               std::to_string(field.step) + ", mic " + fmt3(mic) + ", src " + fmt3(src) +
               (info.layout == data::AudioLayout::soundspaces ? ", heading " : ", source yaw ") +
               std::to_string(yaw).substr(0, std::to_string(yaw).find('.') + 2) + " deg";
  }
  return rir;
}

void add_render_audio_commands(CLI::App& render) {
  add_render_rir(render);
  add_render_loudness(render);
  add_render_trajectory(render);
}

void warn_above_full_scale(const io::AudioBuffer& audio, const std::string& out_path,
                           const std::string& fix) {
  const float peak = dsp::peak_abs(audio);
  if (!(peak > 1.0f)) return;
  std::string ext = std::filesystem::path(out_path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  char level[64];
  std::snprintf(level, sizeof level, "peak %+.1f dBFS", 20.0 * std::log10(peak));
  const std::string also = fix.empty() ? "" : ", or " + fix;
  warn(out_path + ": " + level + " exceeds full scale; " +
       (ext == ".flac" ? "FLAC holds 24-bit integers, so the samples beyond it are clipped: "
                         "write a .wav (32-bit float) to keep them" +
                             also
                       : "the float WAV keeps them, but playback will clip" +
                             (fix.empty() ? "" : "; " + fix)));
}

}  // namespace neraf::cli
