// `neraf train`: trains the radiance and acoustic fields of one scene into a run folder, with
// periodic atomic checkpoints, --resume, and a checkpoint on Ctrl-C. The flags are resolved into
// a TrainConfig by infer::resolve_train_config (infer/train_config.h).
#include <torch/torch.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/infer/train_config.h"
#include "neraf/nerf/config.h"
#include "neraf/train/interrupt.h"
#include "neraf/train/run_training.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::cli {

namespace {

struct TrainArgs {
  std::string data;
  std::string modality = "joint";
  std::string grid = "sampled";
  std::string vision_run;
  double audio_fraction = 1.0;
  int64_t audio_start = -2;
  double decay_loss = 0;
  bool no_relative_geometry = false;
  std::string preset = "cpu";
  int64_t steps = 0;
  uint64_t seed = 42;
  int threads = 0;
  int64_t rays = 0;
  std::string precision;
  std::string out;
  bool resume = false;
  bool force = false;
  bool quiet = false;
};

}  // namespace

void register_train(CLI::App& app) {
  auto args = std::make_shared<TrainArgs>();
  CLI::App* cmd = app.add_subcommand(
      "train",
      "Train a scene's radiance and acoustic fields (posed images + RIRs), jointly by default");
  cmd->footer(
      "Writes RUN/config.json (the resolved config), RUN/data.json (dataset manifest) and\n"
      "RUN/checkpoints/step-XXXXXXXXX.pt. Ctrl-C saves a checkpoint and exits; continue with\n"
      "--resume. The same --seed and --threads give the same numbers.\n"
      "Modalities: joint (default; NeRAF: radiance field + acoustic field, the grid sampled\n"
      "from the radiance field every step), vision (radiance field only), audio (acoustic field\n"
      "on the frozen grid of a finished run: --vision-run RUN, the paper's separate training).\n"
      "Presets: cpu (default; minutes on 2 cores for the simulator's demo room) and paper\n"
      "(exact Nerfacto/NeRAF sizes: 16-level 2^19 hash grid, proposal 256/96, 48 samples).\n"
      "Example: neraf train --data demo/ --out runs/demo");
  CLI::Option* data = cmd->add_option(
      "--data", args->data, "Dataset folder (or its transforms.json); optional with --resume");
  cmd->add_option("--modality", args->modality,
                  "What to train: joint (images + RIRs), vision (images only) or audio (RIRs on "
                  "the frozen field of --vision-run)")
      ->check(CLI::IsMember({"vision", "audio", "joint"}))
      ->capture_default_str();
  CLI::Option* preset = cmd->add_option("--preset", args->preset, "Model and schedule preset")
                            ->check(CLI::IsMember({"cpu", "paper"}))
                            ->capture_default_str();
  CLI::Option* steps =
      cmd->add_option("--steps", args->steps,
                      "Total training steps (default: cpu 3000 joint, 2000 vision, 1500 audio; "
                      "paper 400001 joint, 30000 vision, 398000 audio). With --resume: train on to "
                      "this step")
          ->check(CLI::PositiveNumber);
  CLI::Option* seed = cmd->add_option("--seed", args->seed, "Random seed")->capture_default_str();
  CLI::Option* threads =
      cmd->add_option("--threads", args->threads, "CPU threads (default: all cores)")
          ->check(CLI::PositiveNumber);
  CLI::Option* rays = cmd->add_option("--rays", args->rays,
                                      "Rays per training batch (default: cpu 2048, paper 4096)")
                          ->check(CLI::PositiveNumber);
  CLI::Option* precision =
      cmd->add_option("--precision", args->precision,
                      "MLP matrix products: bf16 (default where the CPU has AVX-512 bf16), fp32, "
                      "or auto")
          ->check(CLI::IsMember({"fp32", "bf16", "auto"}));
  CLI::Option* grid =
      cmd->add_option("--grid", args->grid,
                      "Acoustic scene grid: sampled (from the radiance field, NeRAF), zeros (an "
                      "all-zero grid through the same ResNet3D) or none (no grid input); the "
                      "paper's ablations")
          ->check(CLI::IsMember({"sampled", "none", "zeros"}))
          ->capture_default_str();
  CLI::Option* fraction =
      cmd->add_option("--audio-fraction", args->audio_fraction,
                      "Few-shot: train the acoustic field on this seeded fraction of the training "
                      "RIRs (0 < F <= 1)")
          ->check(CLI::Range(1e-9, 1.0))
          ->capture_default_str();
  CLI::Option* vision_run = cmd->add_option(
      "--vision-run", args->vision_run,
      "With --modality audio: the finished vision (or joint) run whose radiance field fills "
      "the grid (frozen)");
  CLI::Option* audio_start = cmd->add_option(
      "--audio-start-step", args->audio_start,
      "Audio losses start after this step (default: the preset's; cpu 1000, paper 2000; audio "
      "modality 0)");
  CLI::Option* decay_loss =
      cmd->add_option("--decay-loss", args->decay_loss,
                      "Weight of the energy-decay loss on whole RIRs (the paper's \"++\" "
                      "variant; default 0 = off, as the reference)")
          ->check(CLI::NonNegativeNumber);
  CLI::Option* no_relative = cmd->add_flag(
      "--no-relative-geometry", args->no_relative_geometry,
      "Give the acoustic field absolute positions only, as the reference does (the cpu "
      "preset also gives it the source's direction and distance relative to the listener)");
  cmd->add_option("--out", args->out, "Run folder to create (or to resume)")->required();
  cmd->add_flag("--resume", args->resume,
                "Continue the run in --out from its latest checkpoint (uses its config.json)");
  cmd->add_flag("--force", args->force,
                "Start over in a non-empty --out folder (deletes its checkpoints)");
  cmd->add_flag("--quiet", args->quiet, "No progress bar");

  cmd->callback([args, data, preset, steps, seed, threads, rays, precision, grid, fraction,
                 vision_run, audio_start, decay_loss, no_relative]() {
    require(!(args->resume && args->force), "--resume and --force: choose one");
    require(args->resume || data->count() > 0, "--data: required (the dataset folder)");
    // The flags as given (unset: the preset's value for the modality), resolved in one place.
    infer::TrainFlags flags;
    flags.preset = args->preset;
    flags.modality = infer::parse_modality(args->modality);
    if (steps->count()) flags.steps = args->steps;
    flags.seed = args->seed;
    if (threads->count()) flags.threads = args->threads;
    if (rays->count()) flags.rays = args->rays;
    if (precision->count()) flags.precision = nerf::parse_precision(args->precision, "--precision");
    flags.grid = args->grid;
    flags.audio_fraction = args->audio_fraction;
    if (audio_start->count()) flags.audio_start_step = args->audio_start;
    if (decay_loss->count()) flags.decay_loss = args->decay_loss;
    flags.no_relative_geometry = args->no_relative_geometry;
    if (vision_run->count()) flags.vision_run = args->vision_run;
    const infer::TrainConfig cfg = infer::resolve_train_config(flags);
    if (cfg.model.precision == nerf::Precision::bf16 && !nerf::cpu_supports_bf16())
      warn("--precision bf16: this CPU has no native bf16 instructions; expect slow training");

    train::TrainRunOptions opts;
    opts.data_dir = args->data;
    opts.run_dir = args->out;
    opts.resume = args->resume;
    opts.force = args->force;
    opts.progress = !args->quiet;
    if (args->resume) {
      // The run's own config wins; flags that would change the model are refused.
      for (CLI::Option* o : {preset, seed, rays, precision, grid, fraction, vision_run, audio_start,
                             decay_loss, no_relative})
        require(o->count() == 0, o->get_name() +
                                     ": cannot change on --resume (the run's config.json is "
                                     "used); start a new run with --out to change it");
      if (steps->count()) opts.steps = args->steps;
      if (threads->count()) opts.threads = args->threads;
    }
    train::InterruptGuard interrupt;
    opts.stop = &interrupt.flag();
    const train::TrainRunSummary s = train::run_training(cfg, opts);
    if (s.end_step > s.start_step) {
      std::printf("trained steps %lld..%lld in %.1f s (%.2f steps/s)",
                  static_cast<long long>(s.start_step), static_cast<long long>(s.end_step),
                  s.seconds, s.seconds > 0 ? (s.end_step - s.start_step) / s.seconds : 0.0);
      if (cfg.modality != infer::Modality::audio)
        std::printf("; %.0f rays/s, train PSNR %.2f dB", s.rays_per_s, s.last_psnr);
      if (cfg.modality != infer::Modality::vision)
        std::printf("; audio log-mag MSE %.4f", s.last_audio_sl);
      std::printf("; checkpoint %s\n", s.checkpoint.c_str());
    }
  });
}

}  // namespace neraf::cli
