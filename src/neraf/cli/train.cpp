// `neraf train`: trains the radiance field (and, later, the acoustic field) of one scene into a
// run folder, with periodic atomic checkpoints, --resume, and a checkpoint on Ctrl-C.
#include <torch/torch.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/nerf/config.h"
#include "neraf/train/interrupt.h"
#include "neraf/train/run.h"
#include "neraf/train/train_config.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::cli {

namespace {

struct TrainArgs {
  std::string data;
  std::string modality = "vision";
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
      "train", "Train a scene's radiance field from posed images (nerfstudio transforms.json)");
  cmd->footer(
      "Writes RUN/config.json (the resolved config), RUN/data.json (dataset manifest) and\n"
      "RUN/checkpoints/step-XXXXXXXXX.pt. Ctrl-C saves a checkpoint and exits; continue with\n"
      "--resume. The same --seed and --threads give the same numbers.\n"
      "Presets: cpu (default; minutes on 2 cores for the simulator's demo room) and paper\n"
      "(exact Nerfacto/NeRAF sizes: 16-level 2^19 hash grid, proposal 256/96, 48 samples).\n"
      "Example: neraf train --data demo/ --modality vision --out runs/demo");
  CLI::Option* data = cmd->add_option(
      "--data", args->data, "Dataset folder (or its transforms.json); optional with --resume");
  cmd->add_option("--modality", args->modality,
                  "What to train: vision (audio and joint come with the acoustic branch)")
      ->check(CLI::IsMember({"vision", "audio", "joint"}))
      ->capture_default_str();
  CLI::Option* preset = cmd->add_option("--preset", args->preset, "Model and schedule preset")
                            ->check(CLI::IsMember({"cpu", "paper"}))
                            ->capture_default_str();
  CLI::Option* steps =
      cmd->add_option("--steps", args->steps,
                      "Total training steps (default: the preset's; cpu 3000, paper 30000). With "
                      "--resume: train on to this step")
          ->check(CLI::PositiveNumber);
  CLI::Option* seed = cmd->add_option("--seed", args->seed, "Random seed")->capture_default_str();
  CLI::Option* threads =
      cmd->add_option("--threads", args->threads, "CPU threads (default: all cores)")
          ->check(CLI::PositiveNumber);
  CLI::Option* rays = cmd->add_option("--rays", args->rays,
                                      "Rays per training batch (default: the preset's, 4096)")
                          ->check(CLI::PositiveNumber);
  CLI::Option* precision =
      cmd->add_option("--precision", args->precision,
                      "MLP matrix products: bf16 (default where the CPU has AVX-512 bf16), fp32, "
                      "or auto")
          ->check(CLI::IsMember({"fp32", "bf16", "auto"}));
  cmd->add_option("--out", args->out, "Run folder to create (or to resume)")->required();
  cmd->add_flag("--resume", args->resume,
                "Continue the run in --out from its latest checkpoint (uses its config.json)");
  cmd->add_flag("--force", args->force,
                "Start over in a non-empty --out folder (deletes its checkpoints)");
  cmd->add_flag("--quiet", args->quiet, "No progress bar");

  cmd->callback([args, data, preset, steps, seed, threads, rays, precision]() {
    require(!(args->resume && args->force), "--resume and --force: choose one");
    require(args->resume || data->count() > 0, "--data: required (the dataset folder)");
    train::TrainConfig cfg = train::train_preset(args->preset);
    cfg.modality = train::parse_modality(args->modality);
    if (steps->count()) {
      for (train::ScheduleConfig* s : {&cfg.fields, &cfg.proposal_networks})
        if (s->max_steps == cfg.steps) s->max_steps = args->steps;  // decay tied to run length
      cfg.steps = args->steps;
    }
    cfg.seed = args->seed;
    if (threads->count()) cfg.threads = args->threads;
    if (rays->count()) cfg.rays_per_batch = args->rays;
    if (precision->count()) cfg.model.precision = nerf::parse_precision(args->precision, "--precision");
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
      for (CLI::Option* o : {preset, seed, rays, precision})
        require(o->count() == 0, o->get_name() +
                                     ": cannot change on --resume (the run's config.json is "
                                     "used); start a new run with --out to change it");
      if (steps->count()) opts.steps = args->steps;
      if (threads->count()) opts.threads = args->threads;
    }
    train::InterruptGuard interrupt;
    opts.stop = &interrupt.flag();
    const train::TrainRunSummary s = train::run_training(cfg, opts);
    if (s.end_step > s.start_step)
      std::printf("trained steps %lld..%lld in %.1f s (%.0f rays/s); train PSNR %.2f dB; "
                  "checkpoint %s\n",
                  static_cast<long long>(s.start_step), static_cast<long long>(s.end_step),
                  s.seconds, s.rays_per_s, s.last_psnr, s.checkpoint.c_str());
  });
}

}  // namespace neraf::cli
