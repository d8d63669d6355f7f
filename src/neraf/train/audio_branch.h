#pragma once
// The acoustic branch of the trainer (NeRAF joint training, neraf-reference.md §1.4-1.6, §2).
//
// Each step:
//   1. grid update: `cells_per_update` cells of the 7×S³ GridSampler are written from the
//      radiance field (hash-grid input u ∈ [0,1]³, appearance of train image 0, with autograd in
//      joint mode, so the audio loss reaches the field through the fresh cells);
//   2. once step > start_step: a batch of shuffled (RIR, frame) slices of the RirSet train split
//      (epoch-wise permutation without replacement; frames past an RIR's end are the padded
//      log(min + 1e-3) values, as the reference), positions normalised with the train audio aabb,
//      rot encoding, AcousticModel forward, losses "audio_sc_loss" and "audio_mag_loss"
//      (SC+SLMSE, 1e-3·0.1 and 1e-3·1.0).
// Parameter group "audio_fields" = acoustic model params + (joint mode, as the reference) the
// radiance field's params; Adam lr 1e-4 eps 1e-15 with the audio warm-up/decay schedule.
// Modality audio: the radiance field comes from a finished vision run, frozen; the whole grid is
// filled once from it (no per-step updates).
//
// Multi-scene (modality audio, N ≥ 2 scenes; the paper's generalisation over several rooms): one
// grid per scene, filled from that scene's frozen field, and ONE acoustic model (ResNet3D + NAcF)
// over all of them. The epoch permutation runs over every scene's (RIR, frame) slices together,
// so a batch mixes the scenes in proportion to their training RIRs; each scene's slices go
// through ResNet3D on its own grid and NAcF with positions normalised by its own audio box. The
// scenes' features are padded to the longest scene's frames (one time encoding over all), but a
// scene's uniform slices are drawn from its own frames only (scene_frames), so a small room's
// batch share is not spent on padding. One scene (N = 1) is the special case of the same code
// and draws exactly the same numbers.
//
// INFERENCE (render rir / loudness / auralize --run) does not need this class: use
// infer/audio_run.h (load_audio_run + AudioRun::predict_log_stft); the model options and the
// few-shot subset a run trains on are there too (audio_model_options, audio_train_subset).
#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "neraf/acoustic/acoustic_model.h"
#include "neraf/acoustic/grid_sampler.h"
#include "neraf/data/rir_set.h"
#include "neraf/infer/train_config.h"
#include "neraf/train/trainer.h"

namespace neraf::train {

// Consecutive audio steps whose outputs sit (almost) all at ±output_scale. There the tanh has no
// gradient: the field has stopped learning for good while its loss stays finite, which the
// NaN/Inf guard cannot see (seen on the demo room when Adam started at full LR).
struct SaturationWatch {
  int64_t patience = 50;   // steps in a row
  double threshold = 0.9;  // share of saturated outputs in the batch
  int64_t run = 0;
  // The step's share of saturated outputs → true once `patience` steps in a row exceed it.
  bool saturated(double share) {
    run = share > threshold ? run + 1 : 0;
    return run >= patience;
  }
};

class AudioBranch : public Branch {
 public:
  // `field`: the radiance field that fills the grid (the vision branch's model in joint mode, or a
  // frozen model from a vision run in audio mode — then `frozen_field` = true and the grid is
  // filled completely here). `rirs` must have features and outlive the branch. `world_to_field`
  // maps the RIR positions into the field's frame (infer::world_to_field of the scene's images).
  AudioBranch(const infer::TrainConfig& config, const data::RirSet& rirs, nerf::NerfactoModel field,
              const acoustic::WorldToField& world_to_field, bool frozen_field,
              torch::Device device);
  // Multi-scene: scene s has `scenes[s]`, its frozen field `fields[s]`, its map
  // `world_to_field[s]` (N ≥ 1, same sizes; N ≥ 2 needs frozen fields) and its own frames per RIR
  // `scene_frames[s]` (2..max_len; empty: max_len). The RirSets must share channels, frequencies
  // and frames per RIR.
  AudioBranch(const infer::TrainConfig& config, const std::vector<const data::RirSet*>& scenes,
              const std::vector<nerf::NerfactoModel>& fields,
              const std::vector<acoustic::WorldToField>& world_to_field, bool frozen_field,
              torch::Device device, const std::vector<int64_t>& scene_frames = {});

  std::string name() const override { return "audio"; }
  std::vector<ParamGroup> param_groups() override;
  LossDict losses(StepContext& ctx) override;
  void set_training(bool training) override;
  // Weight averaging (config audio.average_fraction > 0): adds the acoustic model's weights after
  // each audio step of the run's last average_fraction of audio steps to their running mean. A
  // step before that window (a resumed run made longer) starts the mean over.
  void after_step(int64_t step, int64_t total_steps) override;
  // Saves "model" (AcousticModel, the last step's weights), "grid" (GridSampler: grid + pointer)
  // and the data sampler ("perm", "cursor") so a killed run resumes exactly; once averaging has
  // begun "model_average" (the same model with the averaged parameters, which inference loads
  // instead: infer/audio_run.h) and "average_steps"; scene s ≥ 1 of a multi-scene run adds
  // "grid_s", "manifest_s", "train_rirs_s" and "num_scenes" (infer::scene_key). (The energy
  // calibration is a stage of its own after training: infer/calibration.h.)
  void save(torch::serialize::OutputArchive& archive) override;
  void load(torch::serialize::InputArchive& archive, const std::string& where) override;

  acoustic::AcousticModel& model() { return model_; }
  acoustic::GridSampler& grid(size_t scene = 0) { return scenes_[scene].grid; }
  const std::vector<int64_t>& train_rirs(size_t scene = 0) const {
    return scenes_[scene].train_rirs;
  }
  size_t num_scenes() const { return scenes_.size(); }
  int64_t averaged_steps() const { return averaged_steps_; }
  // The radiance-field query the grid of `scene` uses (density, rgb at u with train image 0's
  // appearance).
  acoustic::FieldQueryFn field_query(size_t scene = 0);

 private:
  struct Scene {
    const data::RirSet* rirs = nullptr;
    nerf::NerfactoModel field{nullptr};
    acoustic::GridSampler grid{nullptr};
    std::vector<int64_t> train_rirs;  // indices into rirs->rirs
    int64_t offset = 0;               // position of its first train RIR among all scenes'
    int64_t frames = 0;               // its own frames per RIR (uniform slices are drawn below)
    int64_t first_slice = 0;          // position of its first slice in the epoch permutation
    acoustic::NacfOptions nacf;  // the model's NAcF options with this scene's box and world map
  };
  // The step's (train RIR, frame) pairs, each [B + D·T] int64, the RIR as a position among all
  // scenes' train RIRs (scene s owns [offset, offset + its count)): batch_size slices (the
  // uniform share from the epoch permutation over every scene's own slices, then the early
  // share), then D whole RIRs for the energy-decay loss (D = 0 when it is off).
  std::pair<torch::Tensor, torch::Tensor> sample_slices(at::Generator& gen, int64_t D);
  // Multi-scene losses' forward: the slices sorted by scene within the batch and the whole-RIR
  // part (each scene's ResNet3D feature once, NAcF in its box) → {pred, gt}, each [B + D·T, C, F].
  std::pair<torch::Tensor, torch::Tensor> forward_scenes(const torch::Tensor& pos,
                                                         const torch::Tensor& frame, int64_t B);

  infer::TrainConfig config_;
  bool frozen_;
  torch::Device device_;
  acoustic::AcousticModel model_{nullptr};
  std::vector<Scene> scenes_;
  int64_t n_train_ = 0;   // train RIRs of all scenes
  int64_t n_slices_ = 0;  // their (RIR, frame) slices, each scene's own frames
  torch::Tensor perm_;    // [n_slices] int64: this epoch's slice order
  int64_t cursor_ = 0;    // next position in perm_
  torch::Tensor batch_;   // [B + D·T, C, F] float32 gather buffer
  SaturationWatch saturation_;
  // Weight averaging: a model of the same options whose parameters are the running mean (its
  // buffers are copied from model_ when saved); null until averaging begins.
  acoustic::AcousticModel average_{nullptr};
  int64_t averaged_steps_ = 0;  // steps in the mean
};

}  // namespace neraf::train
