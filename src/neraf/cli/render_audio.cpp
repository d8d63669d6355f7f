// `neraf render rir` and `neraf render loudness`: RIRs and loudness maps from a trained run's
// acoustic field (neraf-reference.md §5). Registered by register_render (render.cpp).
#include "neraf/cli/render_audio.h"

#include <torch/torch.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "neraf/render/loudness.h"
#include "neraf/render/rir.h"
#include "neraf/train/audio_run.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::cli {
namespace {

std::string fmt3(const geometry::Vec3& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.2f, %.2f, %.2f)", p.x, p.y, p.z);
  return buf;
}

std::string aabb_text(const data::Aabb& b) {
  return "x " + std::to_string(b.min.x).substr(0, 6) + ".." + std::to_string(b.max.x).substr(0, 6) +
         ", y " + std::to_string(b.min.y).substr(0, 6) + ".." +
         std::to_string(b.max.y).substr(0, 6) + ", z " + std::to_string(b.min.z).substr(0, 6) +
         ".." + std::to_string(b.max.z).substr(0, 6);
}

// A usage error (exit 2) naming the flag.
geometry::Vec3 parse_flag_position(const std::string& text, const std::string& flag) {
  try {
    return render::parse_position(text, flag);
  } catch (const Error& e) {
    throw CLI::ValidationError(e.what());
  }
}

render::AudioModelInfo model_info(const train::AudioRunInfo& i) {
  render::AudioModelInfo m;
  m.layout = i.layout;
  m.sample_rate = i.sample_rate;
  m.stft = i.stft;
  m.channels = i.channels;
  m.max_len = i.max_len;
  m.aabb = i.aabb;
  return m;
}

render::LogStftFn bind(const train::AudioRun& run) {
  return [&run](const torch::Tensor& mic, const torch::Tensor& src, const torch::Tensor& yaw) {
    return run.predict_log_stft_batch(mic, src, yaw);
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

void warn_outside(const geometry::Vec3& p, const std::string& flag, const data::Aabb& box) {
  if (!render::inside_open_box(p, box)) {
    warn(flag + " " + fmt3(p) + " is outside the run's audio bounding box (" + aabb_text(box) +
         ", the train microphones ± 1 m); NeRAF replaces such a position by zeros, so the "
         "prediction does not describe this position");
  }
}

struct LoudnessArgs {
  std::string run;
  AudioPoseArgs pose;
  std::string out;
  std::string csv;
  double spacing = 0.1;
  double height = std::numeric_limits<double>::quiet_NaN();
  int threads = 0;
};

void add_render_rir(CLI::App& render) {
  struct Args {
    std::string run;
    AudioPoseArgs pose;
    std::string out;
    int threads = 0;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = render.add_subcommand(
      "rir", "Render the room impulse response of a trained acoustic field at a pose (WAV)");
  cmd->footer(
      audio_pose_help() +
      "\nThe predicted log-magnitude STFT becomes clip(exp(x) - 1e-3, 0, 1e4) and a waveform "
      "by\nGriffin-Lim (32 iterations, momentum 0.99, random phases from --seed), written "
      "as a\n32-bit float WAV at the run's sample rate (22050 Hz SoundSpaces, 2 channels "
      "binaural;\n48000 Hz RAF, mono), hop*(T-1) samples long.\n"
      "Example: neraf render rir --run runs/demo --mic 2.0,1.5,1.6 --src 1.1,1.2,0.9 "
      "--yaw 90 --out rir.wav");
  cmd->add_option("--run", args->run, "Run folder made by neraf train (joint or audio)")
      ->required();
  add_audio_pose_options(cmd, args->pose, true);
  cmd->add_option("--out", args->out, "Output WAV (written atomically)")->required();
  cmd->add_option("--threads", args->threads, "CPU threads (default: all cores)")
      ->check(CLI::PositiveNumber);
  cmd->callback([args] {
    if (args->threads > 0) torch::set_num_threads(args->threads);
    std::string summary;
    const io::AudioBuffer rir = render_rir_from_run(args->run, args->pose, &summary);
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
      "Example: neraf render loudness --run runs/demo --src 1.1,1.2,0.9 --out loudness.png");
  cmd->add_option("--run", args->run, "Run folder made by neraf train (joint or audio)")
      ->required();
  add_audio_pose_options(cmd, args->pose, false);
  cmd->add_option("--out", args->out, "Output PNG (written atomically)")->required();
  cmd->add_option("--csv", args->csv, "Where to write the values (default: --out with .csv)");
  cmd->add_option("--spacing", args->spacing,
                  "Grid spacing in metres (default 0.1, as the reference; made coarser "
                  "automatically when the grid would exceed 2500 positions)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--height", args->height,
                  "Microphone height y in metres (default: the middle of the train microphones' "
                  "heights, i.e. their height when they share one)");
  cmd->add_option("--threads", args->threads, "CPU threads (default: all cores)")
      ->check(CLI::PositiveNumber);
  cmd->callback([args] {
    if (args->threads > 0) torch::set_num_threads(args->threads);
    const geometry::Vec3 src = parse_flag_position(args->pose.src, "--src");
    const train::AudioRun run =
        train::load_audio_run(args->run, torch::kCPU, args->pose.checkpoint);
    const train::AudioRunInfo& info = run.info();
    const double yaw = resolve_yaw(args->pose, info.layout, args->run);
    warn_outside(src, "--src", info.aabb);
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
        render::compute_loudness_map(bind(run), grid, src, yaw, 64, true);
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
        v.max().item<double>(), secs, static_cast<long long>(run.step()));
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
         "Positions outside the run's audio bounding box (train microphones +- 1 m) are zeroed\n"
         "by NeRAF; a warning says so.\n";
}

std::pair<CLI::Option*, CLI::Option*> add_audio_pose_options(CLI::App* cmd, AudioPoseArgs& a,
                                                             bool with_mic, bool required,
                                                             CLI::Option* needs) {
  const CLI::Validator finite(
      [](std::string& s) {
        char* end = nullptr;
        const double v = std::strtod(s.c_str(), &end);
        return (end != s.c_str() && *end == '\0' && std::isfinite(v))
                   ? std::string()
                   : std::string("must be a finite number of degrees");
      },
      "DEG");
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
          ->check(finite);
  a.src_yaw_opt =
      cmd->add_option("--src-yaw", a.src_yaw, "Source yaw in degrees (RAF runs; default 0)")
          ->check(finite);
  opts.push_back(a.yaw_opt);
  opts.push_back(a.src_yaw_opt);
  if (with_mic) {  // an RIR is rendered: Griffin-Lim needs a seed
    opts.push_back(cmd->add_option("--seed", a.seed,
                                   "Seed of Griffin-Lim's random initial phases (default 0)"));
  }
  opts.push_back(cmd->add_option("--checkpoint", a.checkpoint,
                                 "A specific checkpoint file (default: the run's latest)"));
  for (CLI::Option* o : opts) {
    if (required && (o == mic || o == src)) o->required();
    if (needs) o->needs(needs);
  }
  return {mic, src};
}

io::AudioBuffer render_rir_from_run(const std::string& run_dir, const AudioPoseArgs& args,
                                    std::string* summary) {
  const geometry::Vec3 mic = parse_flag_position(args.mic, "--mic");
  const geometry::Vec3 src = parse_flag_position(args.src, "--src");
  const train::AudioRun run = train::load_audio_run(run_dir, torch::kCPU, args.checkpoint);
  const train::AudioRunInfo& info = run.info();
  const double yaw = resolve_yaw(args, info.layout, run_dir);
  warn_outside(mic, "--mic", info.aabb);
  warn_outside(src, "--src", info.aabb);
  render::RirRenderOptions o;
  o.seed = args.seed;
  const io::AudioBuffer rir = render::render_rir(bind(run), model_info(info), mic, src, yaw, o);
  if (summary) {
    *summary = std::string(data::to_string(info.layout)) + " run, step " +
               std::to_string(run.step()) + ", mic " + fmt3(mic) + ", src " + fmt3(src) +
               (info.layout == data::AudioLayout::soundspaces ? ", heading " : ", source yaw ") +
               std::to_string(yaw).substr(0, std::to_string(yaw).find('.') + 2) + " deg";
  }
  return rir;
}

void add_render_audio_commands(CLI::App& render) {
  add_render_rir(render);
  add_render_loudness(render);
}

}  // namespace neraf::cli
