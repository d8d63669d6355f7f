#pragma once
// A training run folder:
//   RUN/config.json                   the resolved TrainConfig (what --resume, render and eval use)
//   RUN/data.json                     data manifest: dataset path, frames, image size, the world
//                                     normalisation and the eval cameras (render needs no dataset)
//   RUN/checkpoints/step-*.pt         atomic checkpoints (periodic, final, and on Ctrl-C)
// run_training() drives a Trainer over such a folder; load_run() gives render/eval the model.
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>

#include "neraf/data/image_set.h"
#include "neraf/nerf/nerfacto_model.h"
#include "neraf/train/train_config.h"

namespace neraf::train {

struct TrainRunOptions {
  std::string data_dir;  // dataset folder or transforms.json
  std::string run_dir;
  bool resume = false;  // continue from the latest checkpoint in run_dir
  bool force = false;   // start over in a non-empty run_dir (its checkpoints are deleted)
  std::optional<int64_t> steps;       // on resume: a new total step count
  std::optional<int> threads;         // on resume: a different thread count (numbers then differ)
  bool progress = true;
  const std::atomic<bool>* stop = nullptr;  // set asynchronously (Ctrl-C) → checkpoint and return
  torch::Device device = torch::kCPU;
};

struct TrainRunSummary {
  int64_t start_step = 0;
  int64_t end_step = 0;
  double seconds = 0;        // wall time of the optimisation loop (excluding data loading)
  double rays_per_s = 0;
  double last_loss = 0;
  double last_psnr = 0;      // training-batch PSNR, mean over the last 50 steps
  double last_audio_sl = 0;  // audio log-magnitude MSE (running mean; 0 before audio starts)
  bool interrupted = false;
  std::string checkpoint;    // the last checkpoint written
};

// Trains `config` (already resolved from preset + flags) into options.run_dir. On resume the
// run's own config.json is used instead (options.steps/threads may override those two).
TrainRunSummary run_training(const TrainConfig& config, const TrainRunOptions& options);

// The data manifest written to RUN/data.json.
nlohmann::json make_data_manifest(const data::ImageSet& images, const std::string& data_dir);

// A trained run, ready for rendering (model in eval mode on `device`).
struct LoadedRun {
  std::string run_dir;
  TrainConfig config;
  nlohmann::json manifest;  // RUN/data.json
  std::string checkpoint;
  int64_t step = 0;
  nerf::NerfactoModel model{nullptr};
};
// Latest checkpoint of RUN (or `checkpoint` if given). neraf::Error when RUN is not a run folder,
// has no checkpoint, or the checkpoint is corrupted / from another config.
LoadedRun load_run(const std::string& run_dir, torch::Device device = torch::kCPU,
                   const std::string& checkpoint = "");

// The eval cameras stored in the manifest: c2w [N, 3, 4] (normalised frame) and intrinsics.
torch::Tensor manifest_eval_poses(const nlohmann::json& manifest);
// eval_index −1: the default camera (first training frame).
data::Intrinsics manifest_intrinsics(const nlohmann::json& manifest, int64_t eval_index);
// {"fx","fy","cx","cy","width","height"[,"k1","k2","k3","p1","p2"]} ↔ Intrinsics (checked;
// errors name `where`).
data::Intrinsics intrinsics_from_json(const nlohmann::json& j, const std::string& where);
nlohmann::json intrinsics_json(const data::Intrinsics& k);

}  // namespace neraf::train
