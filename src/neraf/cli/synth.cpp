// `neraf synth`: a simulated audio-visual dataset (photos + RIRs) in the SoundSpaces or RAF layout.
#include <omp.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/io/atomic_file.h"
#include "neraf/io/json_file.h"
#include "neraf/sim/occlusion.h"
#include "neraf/sim/plan_drawing.h"
#include "neraf/sim/presets.h"
#include "neraf/sim/scene_json.h"
#include "neraf/sim/synthesize.h"
#include "neraf/util/error.h"
#include "neraf/util/progress.h"

namespace neraf::cli {

namespace {

struct SynthArgs {
  // layout "": the preset's (sim::preset_layout), soundspaces for a scene file.
  std::string scene_file, preset, layout, out_dir, hrtf, mics, gain_from, plan_only;
  int64_t mic_count = 0;
  uint64_t seed = 0;
  int threads = 0;
  bool force = false, quiet = false, print_scene = false, dry_run = false;
};

std::string preset_list() {
  std::string s;
  for (const auto& n : sim::preset_names()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

void run_synth(SynthArgs a) {
  require(a.scene_file.empty() != a.preset.empty(),
          "synth: give exactly one of --scene FILE.json or --preset NAME (" + preset_list() + ")");
  sim::Scene scene = a.preset.empty() ? sim::load_scene(a.scene_file) : sim::preset_scene(a.preset);
  if (!a.mics.empty()) scene.microphones.kind = a.mics;
  require(a.mic_count == 0 || scene.microphones.kind == "random",
          "--mic-count: only used with random microphones; add --mics random");
  if (a.mic_count > 0) scene.microphones.random.count = a.mic_count;
  const std::string where = a.preset.empty() ? a.scene_file : "preset " + a.preset;
  if (a.layout.empty()) a.layout = a.preset.empty() ? "soundspaces" : sim::preset_layout(a.preset);
  if (!a.preset.empty() || !a.mics.empty() || a.mic_count > 0) sim::validate_scene(scene, where);
  require(a.hrtf.empty() || a.layout == "soundspaces",
          "--hrtf: only the soundspaces layout is binaural; the " + a.layout +
              " layout's RIRs are mono, so drop --hrtf (or use --layout soundspaces)");
  if (a.print_scene) {
    std::printf("%s\n", sim::scene_to_json(scene).dump(2).c_str());
    return;
  }
  // Before the plan (a million microphones would already be gigabytes of jobs) and before --out.
  sim::check_synthesis_size(scene, a.layout, where, "--mics, --mic-count");
  if (!a.plan_only.empty()) {
    require_safe_output({"--plan-only", a.plan_only}, {{"--scene", a.scene_file}});
    require_extension({"--plan-only", a.plan_only}, ".png");
    const sim::SynthPlan plan = sim::plan_synthesis(scene, a.layout, a.seed);
    sim::write_plan_png(a.plan_only, sim::draw_plan(scene, plan));
    std::printf("wrote the plan of scene \"%s\" (%s layout, %zu RIRs) to %s\n", scene.name.c_str(),
                plan.layout.c_str(), plan.jobs.size(), a.plan_only.c_str());
    return;
  }
  // Before --out and before any work (synthesize checks it too, naming the scene, not the file).
  const sim::SynthPlan plan = sim::plan_synthesis(scene, a.layout, a.seed);
  sim::check_sound_reaches_microphones(scene, plan, where);
  if (a.dry_run) {
    std::printf(
        "scene \"%s\", %s layout: %zu RIRs (%zu microphone positions x %zu heading(s) x %zu "
        "source(s)), %d channel(s) at %d Hz, %.3g s each; %zu + %zu images at %dx%d\n",
        scene.name.c_str(), plan.layout.c_str(), plan.jobs.size(), plan.microphones.size(),
        plan.binaural ? plan.headings_deg.size() : size_t{1}, scene.sources.size(),
        plan.binaural ? 2 : 1, plan.sample_rate, scene.acoustics.rir_length_s,
        plan.train_cameras.size(), plan.eval_cameras.size(), scene.cameras.width,
        scene.cameras.height);
    if (!scene.furniture.empty()) {
      const sim::DirectPathCount d = sim::count_blocked_direct_paths(scene, plan);
      std::printf(
          "direct path blocked by a box for %lld of %lld source-microphone pairs (%.1f %%)\n",
          static_cast<long long>(d.blocked), static_cast<long long>(d.pairs), 100.0 * d.share());
    }
    return;
  }
  require(!a.out_dir.empty(), "synth: --out DIR is required (the dataset folder to create)");
  io::require_creatable(a.out_dir);
  if (a.threads > 0) omp_set_num_threads(a.threads);

  sim::SynthOptions opt;
  opt.layout = a.layout;
  opt.out_dir = a.out_dir;
  opt.seed = a.seed;
  opt.force = a.force;
  opt.progress = !a.quiet;
  opt.hrtf_path = a.hrtf;
  if (!a.gain_from.empty()) {
    const std::optional<double> gain = sim::synthesized_gain(a.gain_from);
    require(gain.has_value(), "--gain-from " + a.gain_from +
                                  ": no synth_info.json; give a folder written by neraf synth");
    opt.gain = *gain;
    // A binaural and a mono set are not at one scale (the HRTF changes the level).
    const std::string info_path = a.gain_from + "/synth_info.json";
    const nlohmann::json info = io::read_json(info_path);
    const std::string other = info.contains("layout") && info["layout"].is_string()
                                  ? info["layout"].get<std::string>()
                                  : "";
    require(other.empty() || other == a.layout,
            "--gain-from " + a.gain_from + ": is a " + other + " set; give a " + a.layout +
                " set of the same room (--layout " + a.layout + ")");
    // Another room's gain puts this one at an arbitrary scale (its loudest pair is elsewhere).
    if (const std::optional<std::string> differs = sim::room_difference(scene, a.gain_from))
      throw Error("--gain-from " + a.gain_from + ": is another room than " + where + " (" +
                  *differs +
                  " differs in scene.json); give a folder synthesised from the same "
                  "scene");
  }
  const sim::SynthSummary s = sim::synthesize(scene, opt);

  std::printf("synthesised scene \"%s\" in the %s layout into %s\n", scene.name.c_str(),
              s.layout.c_str(), s.out_dir.c_str());
  std::printf(
      "  RIRs:   %lld (%lld train / %lld test), %d channel(s) at %d Hz, %d microphone positions",
      static_cast<long long>(s.num_rirs), static_cast<long long>(s.num_train_rirs),
      static_cast<long long>(s.num_test_rirs), s.channels, s.sample_rate, s.num_microphones);
  if (s.layout == "soundspaces") std::printf(" x %d headings", s.num_headings);
  std::printf(" x %d source(s); gain %.4g, peak %.3f\n", s.num_sources, s.gain, s.peak);
  std::printf("  images: %d train / %d eval at %dx%d\n", s.num_train_images, s.num_eval_images,
              scene.cameras.width, scene.cameras.height);
  std::printf("  time:   %s total (images %s, RIRs %s) on %d thread(s)\n",
              format_duration(s.total_seconds).c_str(), format_duration(s.image_seconds).c_str(),
              format_duration(s.rir_seconds).c_str(), omp_get_max_threads());
}

}  // namespace

void register_synth(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* cmd = app.add_subcommand(
      "synth",
      "Simulate an audio-visual dataset of a room: photos (ray-cast, textured, lit) and room "
      "impulse "
      "responses (image sources + late reverb; binaural with an HRTF for the soundspaces layout, "
      "mono for raf), written in the folder layout NeRAF reads. The room is a scene JSON "
      "(docs/SCENE_FORMAT.md) or a preset. Same seed -> byte-identical files.");
  cmd->add_option("--scene", args->scene_file, "Scene description (JSON, see docs/SCENE_FORMAT.md)")
      ->check(CLI::ExistingFile);
  cmd->add_option(
      "--preset", args->preset,
      "Built-in scene instead of --scene (docs/SCENE_FORMAT.md): demo (small furnished room, "
      "trains in minutes), shoebox (empty room), furnished (larger room, more data), occluded "
      "(a partition with a doorway blocks the direct path), furnished_room / empty_room (one "
      "RAF-like room with and without furniture), small_dead / large_live (size and "
      "absorption), apartment (5 rooms, >= 20,000 binaural RIRs), raf_large (20,000 mono RIRs)");
  cmd->add_option("--layout", args->layout,
                  "Output layout: soundspaces (binaural 44.1 kHz RIRs, 4 headings, "
                  "train_/eval_ images) or raf (mono 48 kHz RIRs, directional sources, "
                  "frame_ images split 90/10 by the reader). Default: raf for the presets "
                  "furnished_room, empty_room and raf_large, soundspaces otherwise")
      ->check(CLI::IsMember({"soundspaces", "raf"}));
  cmd->add_option("--mics", args->mics,
                  "Microphone placement instead of the scene's: grid (SoundSpaces-like regular "
                  "grid) or random (the scene's microphones.random settings). The same room "
                  "with random microphones tests a trained run at new positions: neraf eval "
                  "--novel-data DIR")
      ->check(CLI::IsMember({"grid", "random"}));
  cmd->add_option("--mic-count", args->mic_count,
                  "Number of random microphone positions (with --mics random; the dataset's "
                  "size is checked against the limits before anything is written)")
      ->transform(whole_number(1, 1000000));
  cmd->add_option("--gain-from", args->gain_from,
                  "Scale the RIRs by the gain of this earlier synth folder instead of putting "
                  "the peak at 0.5, so both sets share one scale (needed by eval --novel-data)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", args->out_dir, "Output folder (created; must be empty unless --force)");
  cmd->add_option("--seed", args->seed,
                  "Seed of every random choice (camera and random-microphone placement, splits, "
                  "late-reverb noise)")
      ->transform(seed_number())
      ->capture_default_str();
  cmd->add_option("--threads", args->threads,
                  "Worker threads (default: all cores; at most 4 x the cores)")
      ->transform(thread_count());
  cmd->add_option("--hrtf", args->hrtf,
                  "SOFA file of the binaural HRTF (default: libmysofa's MIT KEMAR default.sofa)")
      ->check(CLI::ExistingFile);
  cmd->add_flag(
      "--force", args->force,
      "Replace a non-empty --out folder (the new dataset is built beside it and swapped in when "
      "complete; the old folder and everything in it is then deleted)");
  cmd->add_flag("--quiet", args->quiet, "No progress bars");
  cmd->add_flag("--print-scene", args->print_scene,
                "Print the resolved scene JSON (e.g. of a preset, to edit and pass back with "
                "--scene) and exit");
  cmd->add_option("--plan-only", args->plan_only,
                  "Draw the top-down plan of the scene (walls, furniture, microphones, sources, "
                  "cameras; as the dataset's plan.png) into this PNG file and exit without "
                  "synthesising");
  cmd->add_flag("--dry-run", args->dry_run,
                "Print how many RIRs and images the scene gives in this layout (and how many "
                "direct paths furniture or walls block) and exit (writes nothing)");
  cmd->callback([args] {
    require(args->plan_only.empty() || args->out_dir.empty(),
            "--plan-only: draws the plan without synthesising; drop --out (a synthesised "
            "dataset gets its plan as DIR/plan.png)");
    require(args->plan_only.empty() || !(args->dry_run || args->print_scene),
            "--plan-only: give it alone, without --dry-run or --print-scene");
    run_synth(*args);
  });
}

}  // namespace neraf::cli
