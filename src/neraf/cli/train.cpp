// `neraf train`: trains the radiance and acoustic fields of one scene into a run folder, with
// periodic atomic checkpoints, --resume, and a checkpoint on Ctrl-C. The flags are resolved into
// a TrainConfig by infer::resolve_train_config (infer/train_config.h).
#include <torch/torch.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/infer/train_config.h"
#include "neraf/nerf/config.h"
#include "neraf/train/distributed.h"
#include "neraf/train/interrupt.h"
#include "neraf/train/run_training.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::cli {

namespace {

struct TrainArgs {
  std::vector<std::string> data;  // one per scene (2+ make a multi-scene audio run)
  std::string modality = "joint";
  std::string grid = "sampled";
  std::string grid_features = "global";
  std::vector<std::string> vision_run;
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
  std::string cache_dir;
  std::string cache_precision = "fp32";
  CLI::Option* cache_dir_opt = nullptr;
  CLI::Option* cache_precision_opt = nullptr;
  int64_t max_len = 0;
  CLI::Option* max_len_opt = nullptr;
  std::string audio_loss = "sc_slmse";
  CLI::Option* audio_loss_opt = nullptr;
  int64_t grid_resolution = 32;
  CLI::Option* grid_resolution_opt = nullptr;
  double position_max_freq_exp = 1;
  CLI::Option* position_max_freq_exp_opt = nullptr;
  bool decay_heads = false;
  CLI::Option* decay_heads_opt = nullptr;
  double audio_average = 0;
  CLI::Option* audio_average_opt = nullptr;
  CLI::Option* modality_opt = nullptr;
  int keep = 3;
  int64_t save_every = 0;
  int world_size = 1;
  int rank = 0;
  std::string master = "127.0.0.1:29500";
  double dist_timeout = 60;
  std::string dist_interface;
  std::string dist_overlap = "auto";
};

// The flag's own bound; the memory check below is the one that usually applies.
constexpr int64_t kMaxRays = 1000000000;

// Resident memory of one vision step per ray sample (activations and their gradients through the
// hash grids, proposal networks and MLPs), measured on the cpu preset (224 samples per ray): peak
// RSS 0.91 GB at 8192 rays, 1.76 GB at 16384, i.e. ~0.1 MB per ray, ~460 B per sample.
constexpr double kBytesPerRaySample = 500;

// Refuses a --rays batch whose estimated memory exceeds this machine's, before any data is read
// (a 1e8-ray batch otherwise died in LibTorch's allocator after loading the dataset).
void check_batch_memory(const infer::TrainConfig& cfg) {
  if (cfg.modality == infer::Modality::audio) return;  // no rays are cast
  int64_t samples = cfg.model.sampler.nerf_samples;
  for (int n : cfg.model.sampler.proposal_samples) samples += n;
  const double need = double(cfg.rays_per_batch) * double(samples) * kBytesPerRaySample;
  const double have = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
  if (have <= 0 || need <= 0.5 * have) return;
  const int64_t most = static_cast<int64_t>(0.5 * have / (double(samples) * kBytesPerRaySample));
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "--rays %lld: a batch of %lld rays x %lld samples needs about %.3g GB of memory; "
                "the limit is half of this machine's %.3g GB (at most %lld rays); use fewer rays",
                static_cast<long long>(cfg.rays_per_batch),
                static_cast<long long>(cfg.rays_per_batch), static_cast<long long>(samples),
                need / 1e9, have / 1e9, static_cast<long long>(most));
  throw Error(buf);
}

}  // namespace

void register_train(CLI::App& app) {
  auto args = std::make_shared<TrainArgs>();
  CLI::App* cmd = app.add_subcommand(
      "train",
      "Train a scene's radiance and acoustic fields (posed images + RIRs), jointly by default");
  cmd->footer(
      "Writes RUN/config.json (the resolved config), RUN/data.json (dataset manifest) and\n"
      "RUN/checkpoints/step-XXXXXXXXX.pt (the newest --keep), then fits the acoustic field's\n"
      "energy calibration (step-XXXXXXXXX.calibration.pt; see neraf calibrate). Ctrl-C saves a\n"
      "checkpoint and exits; continue with --resume. A second writer on --out is refused.\n"
      "The same --seed and --threads give the same numbers.\n"
      "Modalities: joint (default; NeRAF: radiance field + acoustic field, the grid sampled\n"
      "from the radiance field every step), vision (radiance field only), audio (acoustic field\n"
      "on the frozen grid of a finished run: --vision-run RUN, the paper's separate training).\n"
      "Presets: cpu (default; minutes on 2 cores for the simulator's demo room) and paper\n"
      "(exact Nerfacto/NeRAF sizes: 16-level 2^19 hash grid, proposal 256/96, 48 samples).\n"
      "Multi-scene (the paper's generalisation over rooms): --modality audio with one --data and\n"
      "one --vision-run per scene, in the same order (each vision run trained on its scene):\n"
      "one grid per scene from its own radiance field, one scene encoder and acoustic field for\n"
      "all, batches mixing every scene; the scenes must share layout, sample rate and STFT\n"
      "(frames per RIR: --max-len, else the longest scene's). Render, export and auralize take\n"
      "--scene NAME|INDEX (NAME: the dataset folder's name); eval scores every scene and their\n"
      "mean. Joint multi-scene training is not implemented.\n"
      "Several processes: --world-size N --rank R --master HOST:PORT on each (rank 0 writes\n"
      "the run folder), or neraf launch -n N -- train ... on one machine; README, \"Several\n"
      "processes or machines\".\n"
      "Example: neraf train --data demo/ --out runs/demo\n"
      "         neraf train --modality audio --data a/ --vision-run runs/a-vision --data b/\n"
      "           --vision-run runs/b-vision --out runs/ab");
  CLI::Option* data = cmd->add_option("--data", args->data,
                                      "Dataset folder (or its transforms.json); optional with "
                                      "--resume; once per scene for a multi-scene audio run")
                          ->expected(1)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  args->modality_opt =
      cmd->add_option(
             "--modality", args->modality,
             "What to train: joint (images + RIRs), vision (images only) or audio (RIRs on "
             "the frozen field of --vision-run)")
          ->check(CLI::IsMember({"vision", "audio", "joint"}))
          ->capture_default_str();
  CLI::Option* preset =
      cmd->add_option("--preset", args->preset,
                      "Model and schedule preset: cpu (sized for a few CPU cores, with neraf's "
                      "additions), paper (the published sizes and schedule), reference (the "
                      "published model exactly: its grid directions and BatchNorm too)")
          ->check(CLI::IsMember({"cpu", "paper", "reference"}))
          ->capture_default_str();
  CLI::Option* steps =
      cmd->add_option("--steps", args->steps,
                      "Total training steps (default: cpu 3000 joint, 2000 vision, 1500 audio, "
                      "more audio steps on a large dataset: " +
                          std::to_string(infer::kCpuAudioPasses) +
                          " passes over its (RIR, frame) slices, at most " +
                          std::to_string(infer::kCpuMaxAudioSteps) +
                          " audio steps; paper, reference 400001 joint, 30000 vision, 398000 "
                          "audio). With --resume: train on to this step")
          ->transform(whole_number(1, kMaxSteps));
  CLI::Option* seed = cmd->add_option("--seed", args->seed, "Random seed")
                          ->transform(seed_number())
                          ->capture_default_str();
  CLI::Option* threads = cmd->add_option("--threads", args->threads,
                                         "CPU threads (default: all cores; at most 4 x the cores)")
                             ->transform(thread_count());
  CLI::Option* rays = cmd->add_option("--rays", args->rays,
                                      "Rays per training batch (default: cpu 2048, paper 4096; "
                                      "refused when the batch would not fit in memory)")
                          ->transform(whole_number(1, kMaxRays));
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
  CLI::Option* grid_features =
      cmd->add_option("--grid-features", args->grid_features,
                      "How the acoustic field reads the encoded grid: global (one pooled vector "
                      "per room, NeRAF), local (the scene encoder's volume read at the "
                      "microphone, at the source and along the segment between them, per query; "
                      "the RIR positions must be in the cameras' frame, as neraf synth writes "
                      "them) or both")
          ->check(CLI::IsMember({"global", "local", "both"}))
          ->capture_default_str();
  args->grid_resolution_opt =
      cmd->add_option("--grid-resolution", args->grid_resolution,
                      "S: the acoustic grid's cells per side (default: the preset's, cpu 32, "
                      "paper 128; at least 17, which the scene encoder halves four times)")
          ->transform(whole_number(17, 256));
  args->position_max_freq_exp_opt =
      cmd->add_option("--position-max-freq-exp", args->position_max_freq_exp,
                      "E: the microphone and source position encodings' highest frequency is 2^E "
                      "cycles across the RIRs' box (default: the preset's; cpu 1, paper and "
                      "reference 8); a larger room may want more")
          ->check(real_number(0, 8));
  CLI::Option* fraction =
      cmd->add_option("--audio-fraction", args->audio_fraction,
                      "Few-shot: train the acoustic field on this seeded fraction of the training "
                      "RIRs (0 < F <= 1)")
          ->check(real_number(0, 1, true))
          ->capture_default_str();
  CLI::Option* vision_run =
      cmd->add_option("--vision-run", args->vision_run,
                      "With --modality audio: the finished vision (or joint) run whose radiance "
                      "field fills the grid (frozen); once per --data, in the same order, for a "
                      "multi-scene run")
          ->expected(1)
          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  CLI::Option* audio_start = cmd->add_option("--audio-start-step", args->audio_start,
                                             "Audio losses start after this step (default: the "
                                             "preset's; cpu 1000, paper and reference 2000; audio "
                                             "modality 0)")
                                 ->transform(whole_number(-1, kMaxSteps));
  CLI::Option* decay_loss =
      cmd->add_option("--decay-loss", args->decay_loss,
                      "Weight of the energy-decay loss on whole RIRs (the paper's \"++\" "
                      "variant; default 0 = off, as the reference)")
          ->check(real_number(0, 1000));
  args->audio_loss_opt =
      cmd->add_option("--audio-loss", args->audio_loss,
                      "Acoustic training criterion (the paper's loss study): sc_slmse (spectral "
                      "convergence + log-magnitude MSE, the reference's), sc_sll1 (+ log-magnitude "
                      "L1) or mse (log-magnitude MSE alone)")
          ->check(CLI::IsMember({"sc_slmse", "sc_sll1", "mse"}))
          ->capture_default_str();
  CLI::Option* no_relative = cmd->add_flag(
      "--no-relative-geometry", args->no_relative_geometry,
      "Give the acoustic field absolute positions only, as the reference does (the cpu "
      "preset also gives it the source's direction and distance relative to the listener)");
  args->decay_heads_opt = cmd->add_flag(
      "--decay-heads", args->decay_heads,
      "Give the acoustic field a decay slope per frequency beside each output level, so a "
      "tail's decay rate is stated per query (ours, an experiment; runs trained with it cannot "
      "be exported to the runtime)");
  args->audio_average_opt =
      cmd->add_option("--audio-average", args->audio_average,
                      "Share of the audio steps at the end of the run over which the acoustic "
                      "field's weights are averaged; eval, render and export then use the "
                      "average (ours, an experiment; default 0 = the last step's weights)")
          ->check(real_number(0, 1));
  cmd->add_option("--out", args->out, "Run folder to create (or to resume)")->required();
  cmd->add_flag("--resume", args->resume,
                "Continue the run in --out from its latest checkpoint (uses its config.json)");
  cmd->add_flag("--force", args->force,
                "Start over in a non-empty --out folder (deletes its checkpoints)");
  cmd->add_flag("--quiet", args->quiet, "No progress bar");
  args->cache_dir_opt = cmd->add_option(
      "--cache-dir", args->cache_dir,
      "Folder of the audio feature cache (default: DATA/.neraf_cache, or ~/.cache/neraf when "
      "the dataset is read-only); recorded in config.json, so eval finds it");
  args->cache_precision_opt =
      cmd->add_option("--cache-precision", args->cache_precision,
                      "Audio feature cache values: fp32, or fp16 (half the disk and page cache; "
                      "features rounded to ~1e-3 relative); recorded in config.json")
          ->check(CLI::IsMember({"fp32", "fp16"}))
          ->capture_default_str();
  args->max_len_opt =
      cmd->add_option("--max-len", args->max_len,
                      "SoundSpaces layout: STFT frames per RIR (default: the published value for "
                      "office_4, room_2, apartment_1/2, frl_apartment_2/4 by the dataset folder's "
                      "name, else the longest training RIR); recorded in config.json")
          ->transform(whole_number(2, 100000));
  cmd->add_option("--keep", args->keep,
                  "Checkpoints to keep, the newest (0: keep all; older ones are deleted as new "
                  "ones are written)")
      ->transform(whole_number(0, 1000000))
      ->capture_default_str();
  CLI::Option* save_every =
      cmd->add_option("--save-every", args->save_every,
                      "Write a checkpoint every N steps (default: the preset's, 500 for cpu; "
                      "may change on --resume)")
          ->transform(whole_number(1, kMaxSteps));

  CLI::Option* world_size =
      cmd->add_option("--world-size", args->world_size,
                      "Data-parallel training: the number of processes (ranks), on this machine "
                      "(see neraf launch) or several; every rank trains its share of the same "
                      "global batch")
          ->transform(whole_number(1, 1024))
          ->capture_default_str();
  CLI::Option* rank =
      cmd->add_option("--rank", args->rank,
                      "With --world-size: this process's rank in [0, world size); rank 0 writes "
                      "the run folder")
          ->transform(whole_number(0, 1023));
  CLI::Option* master = cmd->add_option("--master", args->master,
                                        "With --world-size: HOST:PORT where rank 0 listens (a TCP "
                                        "port of rank 0's machine that the others can reach)")
                            ->capture_default_str();
  CLI::Option* dist_timeout =
      cmd->add_option("--dist-timeout", args->dist_timeout,
                      "With --world-size: seconds any rank waits for the others (joining, each "
                      "all-reduce) before stopping with an error")
          ->check(real_number(0.1, 86400))
          ->capture_default_str();
  CLI::Option* dist_interface =
      cmd->add_option("--dist-interface", args->dist_interface,
                      "With --world-size: the network interface for the ranks' traffic (e.g. "
                      "eth0; default: the address this host's name resolves to)");
  CLI::Option* dist_overlap =
      cmd->add_option("--dist-overlap", args->dist_overlap,
                      "With --world-size: on starts each gradient bucket's all-reduce inside the "
                      "backward pass as soon as its gradients are final; off starts them all "
                      "after it (the same result); auto: on unless --master is a loopback "
                      "address (ranks that share one machine's cores ran slower with it)")
          ->check(CLI::IsMember({"auto", "on", "off"}))
          ->capture_default_str();

  cmd->callback([args, data, preset, steps, seed, threads, rays, precision, grid, grid_features,
                 fraction, vision_run, audio_start, decay_loss, no_relative, save_every, world_size,
                 rank, master, dist_timeout, dist_interface, dist_overlap]() {
    if (args->world_size == 1)
      for (CLI::Option* o : {rank, master, dist_timeout, dist_interface, dist_overlap})
        require(o->count() == 0, o->get_name() + ": only with --world-size N (N > 1)");
    require(args->rank < args->world_size, "--rank " + std::to_string(args->rank) +
                                               ": must be below --world-size " +
                                               std::to_string(args->world_size) + " (ranks 0.." +
                                               std::to_string(args->world_size - 1) + ")");
    train::DistributedConfig dist;
    dist.world_size = args->world_size;
    dist.rank = args->rank;
    dist.timeout_s = args->dist_timeout;
    dist.setup_timeout_s = std::max(dist.setup_timeout_s, args->dist_timeout);
    dist.interface = args->dist_interface;
    if (args->world_size > 1) train::parse_master(args->master, "--master", dist);
    dist.overlap_backward =
        args->dist_overlap == "on" ||
        (args->dist_overlap == "auto" && !train::is_loopback_host(dist.master_host));
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
    if (grid_features->count()) flags.grid_features = args->grid_features;
    flags.audio_fraction = args->audio_fraction;
    if (audio_start->count()) flags.audio_start_step = args->audio_start;
    if (decay_loss->count()) flags.decay_loss = args->decay_loss;
    if (args->audio_loss_opt->count()) flags.audio_loss = args->audio_loss;
    if (args->grid_resolution_opt->count()) flags.grid_resolution = args->grid_resolution;
    if (args->position_max_freq_exp_opt->count())
      flags.position_max_freq_exp = args->position_max_freq_exp;
    flags.no_relative_geometry = args->no_relative_geometry;
    flags.decay_heads = args->decay_heads;
    if (args->audio_average_opt->count()) flags.audio_average = args->audio_average;
    flags.vision_runs = args->vision_run;
    require(args->data.size() <= 1 || args->modality == "audio",
            "--data: given " + std::to_string(args->data.size()) +
                " times; multi-scene training is implemented for --modality audio only (train "
                "each scene's vision run first, then one --vision-run per --data)");
    require(args->vision_run.size() <= 1 || args->vision_run.size() == args->data.size(),
            "--vision-run: given " + std::to_string(args->vision_run.size()) + " times for " +
                std::to_string(args->data.size()) +
                " --data; a multi-scene run needs one --vision-run per --data, in the same order");
    require(args->data.size() <= 1 || args->vision_run.size() == args->data.size() ||
                args->modality != "audio",
            "--data: given " + std::to_string(args->data.size()) + " times but " +
                std::to_string(args->vision_run.size()) +
                " --vision-run; a multi-scene run needs one --vision-run per --data, in the "
                "same order");

    if (flags.modality == infer::Modality::vision)
      for (CLI::Option* o :
           {grid, grid_features, args->grid_resolution_opt, args->position_max_freq_exp_opt,
            fraction, audio_start, decay_loss, args->audio_loss_opt, no_relative,
            args->decay_heads_opt, args->audio_average_opt, args->max_len_opt, args->cache_dir_opt,
            args->cache_precision_opt})
        require(o->count() == 0, o->get_name() +
                                     ": sets the acoustic field, which --modality vision does "
                                     "not train; drop it (or train --modality joint)");
    require(args->grid != "none" || args->grid_resolution_opt->count() == 0,
            "--grid-resolution: --grid none has no grid; drop one of them");
    require(args->grid != "none" || args->grid_features == "global",
            "--grid-features: --grid none has no grid to read; drop one of them");
    require_cache_folder({"--cache-dir", args->cache_dir}, args->out);
    infer::TrainConfig cfg = infer::resolve_train_config(flags);
    cfg.audio.cache_dir = args->cache_dir;
    cfg.audio.cache_precision = args->cache_precision;
    cfg.audio.max_len = args->max_len;
    if (!args->resume) check_batch_memory(cfg);
    if (cfg.model.precision == nerf::Precision::bf16 && !nerf::cpu_supports_bf16())
      warn("--precision bf16: this CPU has no native bf16 instructions; expect slow training");

    train::TrainRunOptions opts;
    if (args->data.size() == 1) opts.data_dir = args->data.front();
    if (args->data.size() > 1) opts.scene_data_dirs = args->data;
    for (size_t i = 0; i < args->data.size(); ++i)
      for (size_t j = 0; j < i; ++j) {
        std::error_code ec;
        require(!std::filesystem::equivalent(args->data[i], args->data[j], ec),
                "--data " + args->data[i] + ": given twice (as " + args->data[j] +
                    "); a multi-scene run takes each room once");
      }
    opts.run_dir = args->out;
    opts.resume = args->resume;
    opts.force = args->force;
    opts.progress = !args->quiet;
    opts.keep = args->keep;
    if (save_every->count()) opts.save_every = args->save_every;
    if (args->resume) {
      std::error_code ec;  // rank 0 reads the run (the others get its config)
      require(
          args->rank > 0 || std::filesystem::is_regular_file(
                                (std::filesystem::path(args->out) / "config.json").string(), ec),
          args->out +
              ": no config.json here, so there is no run to resume; drop --resume to start a "
              "new run");
      // The run's own config wins; flags that would change the model are refused.
      for (CLI::Option* o : {preset, seed, rays, precision, grid, grid_features, fraction,
                             vision_run, audio_start, decay_loss, no_relative})
        require(o->count() == 0, o->get_name() +
                                     ": cannot change on --resume (the run's config.json is "
                                     "used); start a new run with --out to change it");
      for (CLI::Option* o :
           {args->cache_dir_opt, args->cache_precision_opt, args->max_len_opt, args->audio_loss_opt,
            args->grid_resolution_opt, args->position_max_freq_exp_opt, args->decay_heads_opt,
            args->audio_average_opt, args->modality_opt})
        require(o->count() == 0, o->get_name() +
                                     ": cannot change on --resume (the run's config.json records "
                                     "it); start a new run with --out to change it");
      if (steps->count()) opts.steps = args->steps;
      if (threads->count()) opts.threads = args->threads;
    }
    opts.distributed = dist;
    train::InterruptGuard interrupt;
    opts.stop = &interrupt.flag();
    const train::TrainRunSummary s = train::run_training(cfg, opts);
    if (dist.rank > 0) return;  // rank 0 reports
    if (s.end_step > s.start_step) {
      std::printf("trained steps %lld..%lld in %.1f s (%.2f steps/s)",
                  static_cast<long long>(s.start_step), static_cast<long long>(s.end_step),
                  s.seconds, s.seconds > 0 ? (s.end_step - s.start_step) / s.seconds : 0.0);
      if (cfg.modality != infer::Modality::audio)
        std::printf("; %.0f rays/s, train PSNR %.2f dB", s.rays_per_s, s.last_psnr);
      if (cfg.modality != infer::Modality::vision)
        std::printf("; audio log-mag MSE %.4f", s.last_audio_sl);
      if (s.comm.allreduces > 0)
        std::printf(
            "; all-reduce %.1f MB/step, %.1f ms/step added (%lld/%lld buckets started "
            "during backward)",
            double(s.comm.bytes) / double(s.comm.allreduces) / 1e6,
            1e3 * s.comm.seconds / double(s.comm.allreduces),
            static_cast<long long>(s.comm.overlapped_buckets),
            static_cast<long long>(s.comm.buckets));
      std::printf("; checkpoint %s\n", s.checkpoint.c_str());
    }
    if (s.interrupted)
      throw Interrupted("training stopped at step " + std::to_string(s.end_step) +
                        " with its checkpoint saved; continue with: neraf train --out " +
                        args->out + " --resume");
  });
}

}  // namespace neraf::cli
