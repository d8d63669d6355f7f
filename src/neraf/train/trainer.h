#pragma once
// The trainer: a step function over "branches" (vision now; the acoustic branch plugs in the
// same way), one Adam optimizer per named parameter group with a pure-function LR schedule,
// and resumable checkpoints.
//
// Adding a branch (e.g. audio, issue 5):
//   1. Subclass `Branch`: name() ("audio"), param_groups() (e.g. "audio_fields" — NeRAF also puts
//      the radiance field's parameters in that group, reachable through
//      `trainer.vision()->model()->field`), losses(ctx) returning named scalar losses (an empty
//      dict before `start_step_audio`), save()/load() for its modules and non-parameter state.
//   2. In `make_trainer` (trainer.cpp) construct it for Modality::audio / joint and
//      `add_branch` it after the vision branch. Branches run in insertion order each step, so the
//      audio branch sees the vision branch's step already taken (grid updates can go in
//      `Branch::losses` of the audio branch).
//   3. Put its config struct in TrainConfig (infer/train_config.h) and its eval in eval/.
// Everything else (optimizers, schedules, checkpoints, resume, SIGINT, progress) is generic.
#include <torch/torch.h>

#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "neraf/data/image_set.h"
#include "neraf/data/rir_set.h"
#include "neraf/infer/train_config.h"
#include "neraf/nerf/nerfacto_model.h"
#include "neraf/util/error.h"

namespace neraf::train {

using LossDict = nerf::LossDict;

// A named set of parameters with its own Adam optimizer and LR schedule (nerfstudio's optimizer
// groups: "fields", "proposal_networks", "camera_opt"; NeRAF adds "audio_fields"). A parameter
// may appear in several groups (each group keeps its own Adam moments, as NeRAF does).
struct ParamGroup {
  std::string name;
  std::vector<torch::Tensor> params;
  infer::ScheduleConfig schedule;
};

class Distributed;  // distributed.h

// This process's share of a data-parallel step (train/distributed.h): every rank draws the same
// global batch from the same generator and works on rows [begin, begin + count) of it.
struct Shard {
  int rank = 0;
  int world_size = 1;
  // Rows of a global batch of n (n must split evenly; checked when the run starts).
  int64_t begin(int64_t n) const { return n / world_size * rank; }
  int64_t count(int64_t n) const { return n / world_size; }
  bool whole() const { return world_size == 1; }
};

// What a branch sees during a step.
struct StepContext {
  int64_t step;                            // index of the step being taken (0-based)
  at::Generator& gen;                      // the run's random stream (checkpointed)
  std::map<std::string, double>& metrics;  // scalars to report (e.g. "psnr")
  Shard shard = {};                        // this rank's rows of the global batch
  // Sums a small tensor in place over the ranks (losses that are not means over the batch);
  // null when the run is not distributed.
  Distributed* dist = nullptr;
};

class Branch {
 public:
  virtual ~Branch() = default;
  virtual std::string name() const = 0;  // checkpoint key prefix: "vision", "audio"
  virtual std::vector<ParamGroup> param_groups() = 0;
  // Forward pass and named losses for this step (summed with the other branches' losses into the
  // objective). May return an empty dict (branch inactive this step).
  virtual LossDict losses(StepContext& ctx) = 0;
  virtual int64_t rays_per_step() const { return 0; }  // throughput report (vision rays)
  // After the optimizers have applied step `step` (0-based; a step with losses) of a run of
  // `total_steps`.
  virtual void after_step(int64_t step, int64_t total_steps) {}
  virtual void set_training(bool training) = 0;
  virtual void save(torch::serialize::OutputArchive& archive) = 0;
  // `where` names the checkpoint file for error messages.
  virtual void load(torch::serialize::InputArchive& archive, const std::string& where) = 0;
};

// Nerfacto on posed images: random pixels over all training images each step.
class VisionBranch : public Branch {
 public:
  VisionBranch(const infer::TrainConfig& config, const data::ImageSplit& train,
               torch::Device device);

  std::string name() const override { return "vision"; }
  std::vector<ParamGroup> param_groups() override;
  LossDict losses(StepContext& ctx) override;
  int64_t rays_per_step() const override { return config_.rays_per_batch; }
  void set_training(bool training) override;
  void save(torch::serialize::OutputArchive& archive) override;
  void load(torch::serialize::InputArchive& archive, const std::string& where) override;

  nerf::NerfactoModel& model() { return model_; }
  // The proposal-schedule state (nerfstudio's steps_since_update).
  int64_t steps_since_update() const { return steps_since_update_; }

 private:
  infer::TrainConfig config_;
  torch::Device device_;
  nerf::NerfactoModel model_{nullptr};
  torch::Tensor pixels_;  // [N·H·W, 3] uint8 on device
  torch::Tensor c2w_;     // [N, 3, 4]
  torch::Tensor intr_;    // [N, 9] (nerf::intrinsics_row)
  int64_t num_images_ = 0, height_ = 0, width_ = 0;
  int64_t steps_since_update_ = 0;
};

// Training diverged: a loss term came out NaN or infinite (the step is not applied), or the
// weights to be saved are not finite (nothing is written). run_training keeps the last
// checkpoint, whose weights were finite.
struct DivergedError : Error {
  using Error::Error;
};

struct StepResult {
  int64_t step = 0;                       // steps completed after this one
  std::map<std::string, double> losses;   // each named loss
  double loss = 0;                        // their sum
  std::map<std::string, double> metrics;  // e.g. "psnr" of the training batch
  int64_t rays = 0;                       // vision rays this step
};

class Trainer {
 public:
  Trainer(infer::TrainConfig config, torch::Device device);

  // Branches must be added before the first step and before load_checkpoint.
  void add_branch(std::unique_ptr<Branch> branch);

  // One optimisation step: LRs from the schedules, zero grads, every branch's losses, backward,
  // every optimizer steps, every branch's after_step. DivergedError naming the term when a loss is
  // not finite (nothing is applied then).
  StepResult step();
  int64_t completed_steps() const { return step_; }

  // Archive layout: "format", "config" (resolved JSON), "step", "rng", "branch/<name>",
  // "optim/<group>". Loading checks that the stored config describes the same model (preset,
  // model, modality) and throws neraf::Error naming the file and the first differing setting.
  // DivergedError (nothing written) when a parameter is not finite.
  void save_checkpoint(const std::string& path);
  void load_checkpoint(const std::string& path);
  // The same from the file's bytes (`path` names it in errors): a distributed run's ranks load
  // what rank 0 read.
  void load_checkpoint_bytes(const std::string& bytes, const std::string& path);

  // Data-parallel training (`dist` outlives the trainer; null: one process): each step works on
  // this rank's share of the global batch and averages the gradients over the ranks; the
  // reported losses and metrics are the ranks' means (identical on every rank, so a non-finite
  // loss stops every rank at the same step).
  void set_distributed(Distributed* dist);
  // Rank 0's parameters on every rank (after construction or loading; the ranks build the same
  // model from the same seed, this makes it certain).
  void broadcast_parameters();

  const infer::TrainConfig& config() const { return config_; }
  void set_total_steps(int64_t steps) { config_.steps = steps; }
  VisionBranch* vision();  // nullptr when the run has no vision branch
  Branch* branch(const std::string& name);
  at::Generator& generator() { return gen_; }
  // Current learning rate of a group (for logs and tests).
  double group_lr(const std::string& name) const;

 private:
  void build_optimizers();
  void load_state(torch::serialize::InputArchive& archive, const std::string& path);

  struct Group {
    std::string name;
    infer::ScheduleConfig schedule;
    std::vector<torch::Tensor> params;
    std::unique_ptr<torch::optim::Adam> optimizer;
  };

  infer::TrainConfig config_;
  torch::Device device_;
  std::vector<std::unique_ptr<Branch>> branches_;
  std::vector<Group> groups_;
  at::Generator gen_;
  int64_t step_ = 0;
  Distributed* dist_ = nullptr;
};

// The trainer for `config.modality` with its branches. Vision/joint need `images`; audio/joint
// need `rirs` (with features; must outlive the trainer). Modality audio loads the frozen
// radiance field from config.audio.vision_run (see audio_branch.h).
std::unique_ptr<Trainer> make_trainer(const infer::TrainConfig& config,
                                      const data::ImageSet* images, torch::Device device,
                                      const data::RirSet* rirs = nullptr);
// A multi-scene audio run (config.audio.vision_runs, N ≥ 2): scene s trains on `scenes[s]` with
// the frozen radiance field of config.audio.vision_runs[s] (audio_branch.h, "Multi-scene"), on
// its first `scene_frames[s]` frames per RIR (empty: all of them).
std::unique_ptr<Trainer> make_multiscene_trainer(const infer::TrainConfig& config,
                                                 const std::vector<const data::RirSet*>& scenes,
                                                 torch::Device device,
                                                 const std::vector<int64_t>& scene_frames = {});

}  // namespace neraf::train
