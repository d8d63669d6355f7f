#include "neraf/infer/train_config.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "neraf/acoustic/acoustic_model.h"
#include "neraf/acoustic/losses.h"
#include "neraf/io/json_file.h"
#include "neraf/nerf/config_io.h"
#include "neraf/util/error.h"
#include "neraf/util/number_text.h"

namespace neraf::infer {

void set_run_length(TrainConfig& c, int64_t steps) {
  for (ScheduleConfig* s : {&c.fields, &c.proposal_networks, &c.audio.schedule})
    if (s->max_steps == c.steps) s->max_steps = steps;
  c.steps = steps;
}

TrainConfig resolve_train_config(const TrainFlags& f) {
  TrainConfig cfg = train_preset(f.preset);
  cfg.modality = f.modality;
  const bool paper = published_sizes(f.preset);
  if (cfg.modality == Modality::joint && paper)
    cfg.steps = 400001;  // NeRAF's max_num_iterations (audio from step 2001)
  if (cfg.modality == Modality::audio) {
    // The radiance field is final (the grid is filled once): audio from the first step.
    cfg.audio.start_step = -1;
    cfg.audio.schedule.warmup_start = 0;
    cfg.audio.schedule.warmup_steps = paper ? 2000 : 100;
    if (paper)
      cfg.steps = 398000;
    else
      set_run_length(cfg, 1500);
  }
  // Vision alone on the cpu preset: 2000 steps (~8 minutes on 2 cores for the demo room);
  // joint runs keep 3000, as the acoustic field starts at step 1000.
  if (cfg.modality == Modality::vision && !paper) set_run_length(cfg, 2000);
  if (f.steps) set_run_length(cfg, *f.steps);
  cfg.steps_from_data = !f.steps && !paper && cfg.modality != Modality::vision;
  cfg.seed = f.seed;
  if (f.audio_start_step) {
    if (cfg.audio.schedule.warmup_start == std::max<int64_t>(0, cfg.audio.start_step))  // from it
      cfg.audio.schedule.warmup_start = std::max<int64_t>(0, *f.audio_start_step);
    else if (cfg.audio.schedule.warmup_steps == cfg.audio.start_step)  // ... or up to it
      cfg.audio.schedule.warmup_steps = std::max<int64_t>(0, *f.audio_start_step);
    cfg.audio.start_step = *f.audio_start_step;
  }
  {  // a short run still gets a (shorter) audio warm-up, ending before the run does
    auto& schedule = cfg.audio.schedule;
    schedule.warmup_steps =
        std::min(schedule.warmup_steps,
                 std::max<int64_t>(0, (schedule.max_steps - schedule.warmup_start) / 2));
  }
  cfg.audio.grid = f.grid;
  if (f.grid_features) cfg.audio.grid_features = *f.grid_features;
  if (f.decay_loss) cfg.audio.decay_weight = *f.decay_loss;
  if (f.audio_average) cfg.audio.average_fraction = *f.audio_average;
  if (f.audio_loss) cfg.audio.loss = *f.audio_loss;
  if (f.grid_resolution) cfg.audio.grid_resolution = *f.grid_resolution;
  if (f.position_max_freq_exp) cfg.audio.position_max_freq_exp = *f.position_max_freq_exp;
  if (f.decay_heads) cfg.audio.decay_heads = true;
  cfg.audio.fraction = f.audio_fraction;
  if (f.no_relative_geometry) cfg.audio.relative_geometry = false;
  require(cfg.modality == Modality::audio || f.vision_runs.empty(),
          "--vision-run: only used with --modality audio");
  auto absolute = [](const std::string& p) {
    return std::filesystem::absolute(p).lexically_normal().string();
  };
  if (!f.vision_runs.empty()) cfg.audio.vision_run = absolute(f.vision_runs.front());
  if (f.vision_runs.size() > 1)
    for (const std::string& r : f.vision_runs) cfg.audio.vision_runs.push_back(absolute(r));
  if (f.threads) cfg.threads = *f.threads;
  if (f.rays) cfg.rays_per_batch = *f.rays;
  if (f.precision) cfg.model.precision = *f.precision;
  return cfg;
}

RunLengthFit fit_run_length_to_data(TrainConfig& c, int64_t train_slices) {
  const int64_t audio_steps = c.steps - std::max<int64_t>(0, c.audio.start_step + 1);
  RunLengthFit fit{audio_steps, audio_steps};
  if (!c.steps_from_data || c.modality == Modality::vision) return fit;
  const double wanted =
      std::ceil(static_cast<double>(kCpuAudioPasses) * static_cast<double>(train_slices) /
                static_cast<double>(std::max<int64_t>(1, c.audio.batch_size)));
  fit.audio_steps_after = std::clamp(static_cast<int64_t>(std::min(wanted, 1e15)), audio_steps,
                                     std::max(audio_steps, kCpuMaxAudioSteps));
  set_run_length(c, c.steps + fit.audio_steps_after - audio_steps);
  return fit;
}

int64_t num_scenes(const TrainConfig& c) {
  return std::max<int64_t>(1, static_cast<int64_t>(c.audio.vision_runs.size()));
}

namespace {
void check_schedule(const ScheduleConfig& s, const std::string& where) {
  require(s.lr > 0 && s.lr_final > 0, where + ": lr and lr_final must be positive");
  // max_steps may end inside the warm-up (a run shortened on --resume): learning_rate copes.
  require(s.warmup_steps >= 0 && s.warmup_start >= 0 && s.max_steps >= 1,
          where + ": need warmup_steps >= 0, warmup_start >= 0 and max_steps >= 1");
  require(s.warmup_ramp == "linear" || s.warmup_ramp == "sine",
          where + ".warmup_ramp: use linear or sine");
  require(s.eps > 0, where + ".eps: must be positive");
}
}  // namespace

void validate(const TrainConfig& c, const std::string& where) {
  require(c.steps >= 1, where + ".steps: must be at least 1 (--steps)");
  require(c.rays_per_batch >= 1, where + ".rays_per_batch: must be at least 1");
  require(c.threads >= 0 && c.threads <= max_thread_count(),
          where + ".threads: must be from 0 (automatic) to " + std::to_string(max_thread_count()) +
              " (4 x this machine's cores), got " + std::to_string(c.threads) + " (--threads)");
  require(c.save_every >= 1, where + ".save_every: must be at least 1");
  require(c.eval_rays_per_chunk >= 1, where + ".eval_rays_per_chunk: must be at least 1");
  check_schedule(c.fields, where + ".fields");
  check_schedule(c.proposal_networks, where + ".proposal_networks");
  check_schedule(c.camera_opt, where + ".camera_opt");
  nerf::validate(c.model, where + ".model");
  if (c.modality == Modality::vision) return;  // the acoustic settings are unused
  const AudioConfig& a = c.audio;
  require(a.grid == "sampled" || a.grid == "none" || a.grid == "zeros",
          where + ".audio.grid: use sampled, none or zeros (--grid)");
  require(a.grid_features == "global" || a.grid_features == "local" || a.grid_features == "both",
          where + ".audio.grid_features: use global, local or both (--grid-features)");
  require(a.grid != "none" || a.grid_features == "global",
          where + ".audio.grid_features: " + a.grid_features +
              " reads the grid, and --grid none has none (leave --grid-features out)");
  require(a.view_directions == "spread" || a.view_directions == "reference",
          where + ".audio.view_directions: use spread or reference (--preset reference sets it)");
  require(a.resnet_batch_norm == "grid" || a.resnet_batch_norm == "running",
          where + ".audio.resnet_batch_norm: use grid or running (--preset reference sets it)");
  require(a.batch_size >= 1, where + ".audio.batch_size: must be at least 1");
  // The scene encoder halves the grid four times; BatchNorm needs more than one voxel at the end.
  const int64_t min_side =
      acoustic::resnet3d_min_grid_resolution(acoustic::acoustic_preset(c.preset, 1, 1, 1).resnet);
  require(a.grid == "none" || (a.grid_resolution >= min_side && a.grid_resolution <= 256),
          where + ".audio.grid_resolution: must be in [" + std::to_string(min_side) +
              ", 256] for the scene encoder of preset " + c.preset + " (--grid-resolution)");
  require(acoustic::parse_audio_criterion(a.loss).has_value(),
          where + ".audio.loss: use sc_slmse, sc_sll1 or mse (--audio-loss)");
  require(a.cells_per_update >= 1, where + ".audio.cells_per_update: must be at least 1");
  require(a.nacf_width >= 0 && a.nacf_layers >= 1,
          where + ".audio.nacf_width/nacf_layers: must be >= 0 / >= 1");
  require(a.fraction > 0 && a.fraction <= 1, where +
                                                 ".audio.fraction: must be in (0, 1] "
                                                 "(--audio-fraction)");
  require(a.start_step >= -1, where + ".audio.start_step: must be >= -1");
  require(a.decay_weight >= 0 && std::isfinite(a.decay_weight),
          where + ".audio.decay_weight: must be a number >= 0 (--decay-loss)");
  require(a.average_fraction >= 0 && a.average_fraction <= 1,
          where + ".audio.average_fraction: must be in [0, 1] (--audio-average)");
  require(a.decay_rirs >= 1, where + ".audio.decay_rirs: must be at least 1");
  require(a.early_fraction >= 0 && a.early_fraction <= 1,
          where + ".audio.early_fraction: must be in [0, 1]");
  require(a.early_frames >= 1, where + ".audio.early_frames: must be at least 1");
  require(a.max_len == 0 || (a.max_len >= 2 && a.max_len <= 100000),
          where + ".audio.max_len: use 0 (automatic) or 2..100000 frames (--max-len)");
  require(a.cache_precision == "fp32" || a.cache_precision == "fp16",
          where + ".audio.cache_precision: use fp32 or fp16 (--cache-precision)");
  if (c.modality == Modality::audio)
    require(!a.vision_run.empty(), where +
                                       ".audio.vision_run: required with --modality audio "
                                       "(--vision-run)");
  if (!a.vision_runs.empty()) {
    require(c.modality == Modality::audio,
            where +
                ".audio.vision_runs: a multi-scene run trains --modality audio (on each "
                "scene's frozen vision run); joint multi-scene training is not implemented");
    require(a.vision_runs.size() >= 2 && a.vision_runs.front() == a.vision_run,
            where +
                ".audio.vision_runs: needs 2 or more runs, the first equal to "
                "audio.vision_run (one --vision-run per --data)");
  }
  if (c.modality != Modality::vision)
    // Steps are numbered 0..steps−1 and audio runs on those after start_step: at least one.
    require(a.start_step < c.steps - 1,
            where + ".audio.start_step: audio starts after step " + std::to_string(a.start_step) +
                " (--audio-start-step) but the run's steps are 0.." + std::to_string(c.steps - 1) +
                ", so the acoustic field would never train; raise --steps to at least " +
                std::to_string(a.start_step + 2) + " or lower --audio-start-step");
  check_schedule(a.schedule, where + ".audio.schedule");
}

TrainConfig read_run_config(const std::string& config_path) {
  TrainConfig c = train_config_from_json(io::read_json(config_path), config_path);
  TrainConfig checked = c;
  checked.threads = 0;
  validate(checked, config_path);
  return c;
}

}  // namespace neraf::infer
