#pragma once
// Training a run folder (layout: infer/run.h): a Trainer (trainer.h) over the dataset, with
// periodic atomic checkpoints, --resume and a checkpoint on Ctrl-C.
#include <torch/torch.h>

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "neraf/infer/train_config.h"
#include "neraf/train/distributed.h"

namespace neraf::train {

struct TrainRunOptions {
  std::string data_dir;  // dataset folder or transforms.json
  // A multi-scene run (config.audio.vision_runs, N ≥ 2): every scene's dataset in the order of
  // its vision runs (data_dir is then unused); empty for one scene, and on resume (RUN/data.json
  // records them).
  std::vector<std::string> scene_data_dirs;
  std::string run_dir;
  bool resume = false;           // continue from the latest checkpoint in run_dir
  bool force = false;            // start over in a non-empty run_dir (its checkpoints are deleted)
  std::optional<int64_t> steps;  // on resume: a new total step count
  std::optional<int> threads;    // on resume: a different thread count (numbers then differ)
  std::optional<int64_t> save_every;  // a checkpoint every N steps (default: the preset's)
  int keep = 3;                       // checkpoints kept (the newest); 0 keeps all
  bool progress = true;
  const std::atomic<bool>* stop = nullptr;  // set asynchronously (Ctrl-C) → checkpoint and return
  torch::Device device = torch::kCPU;
  // Data-parallel training (world_size > 1, distributed.h): rank 0 owns the run folder (lock,
  // config.json, data.json, checkpoints, calibration, progress); the other ranks never touch
  // it: they take rank 0's config (and on --resume its checkpoint's bytes) over the network and
  // need only their own copy of the dataset (--data, or rank 0's data path on resume).
  DistributedConfig distributed;
};

struct TrainRunSummary {
  int64_t start_step = 0;
  int64_t end_step = 0;
  double seconds = 0;  // wall time of the optimisation loop (excluding data loading)
  double rays_per_s = 0;
  double last_loss = 0;
  double last_psnr = 0;      // training-batch PSNR, mean over the last 50 steps
  double last_audio_sl = 0;  // audio log-magnitude MSE (running mean; 0 before audio starts)
  bool interrupted = false;
  std::string checkpoint;  // the last checkpoint written
  CommStats comm;          // distributed: the gradient all-reduces (bytes, time)
};

// Trains `config` (already resolved from preset + flags) into options.run_dir, holding its lock
// (io/folder_lock.h: a second writer is refused), then calibrates the acoustic field
// (infer/calibration.h) unless interrupted. On resume the run's own config.json is used instead
// (options.steps/threads may override those two) and a damaged latest checkpoint is skipped
// for the one before. A diverged loss (NaN/Inf) stops with neraf::Error naming the term; the
// last checkpoint stays. A multi-scene run loads every scene (one layout, sample rate and STFT;
// each checked against its vision run; frames per RIR made equal) and writes RUN/data.json as
// {"format", "scenes": [...]} (infer/run.h).
TrainRunSummary run_training(const infer::TrainConfig& config, const TrainRunOptions& options);

}  // namespace neraf::train
