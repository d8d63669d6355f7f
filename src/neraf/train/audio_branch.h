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

class AudioBranch : public Branch {
 public:
  // `field`: the radiance field that fills the grid (the vision branch's model in joint mode, or a
  // frozen model from a vision run in audio mode — then `frozen_field` = true and the grid is
  // filled completely here). `rirs` must have features and outlive the branch.
  AudioBranch(const infer::TrainConfig& config, const data::RirSet& rirs, nerf::NerfactoModel field,
              bool frozen_field, torch::Device device);

  std::string name() const override { return "audio"; }
  std::vector<ParamGroup> param_groups() override;
  LossDict losses(StepContext& ctx) override;
  void set_training(bool training) override;
  // Saves "model" (AcousticModel), "grid" (GridSampler: grid + pointer) and the data sampler
  // ("perm", "cursor") so a killed run resumes exactly. (The energy calibration is a stage of
  // its own after training: infer/calibration.h.)
  void save(torch::serialize::OutputArchive& archive) override;
  void load(torch::serialize::InputArchive& archive, const std::string& where) override;

  acoustic::AcousticModel& model() { return model_; }
  acoustic::GridSampler& grid() { return grid_; }
  const std::vector<int64_t>& train_rirs() const { return train_rirs_; }
  // The radiance-field query the grid uses (density, rgb at u with train image 0's appearance).
  acoustic::FieldQueryFn field_query();

 private:
  // The step's (RIR index, frame) pairs, each [B + D·T] int64: batch_size slices (the uniform
  // share from the epoch permutation, then the early share), then D whole RIRs for the
  // energy-decay loss (D = 0 when it is off).
  std::pair<torch::Tensor, torch::Tensor> sample_slices(at::Generator& gen, int64_t D);

  infer::TrainConfig config_;
  const data::RirSet& rirs_;
  nerf::NerfactoModel field_;
  bool frozen_;
  torch::Device device_;
  acoustic::AcousticModel model_{nullptr};
  acoustic::GridSampler grid_{nullptr};
  std::vector<int64_t> train_rirs_;  // indices into rirs_.rirs
  torch::Tensor perm_;               // [n_train·max_len] int64: this epoch's slice order
  int64_t cursor_ = 0;               // next position in perm_
  torch::Tensor batch_;              // [B + D·T, C, F] float32 gather buffer
};

}  // namespace neraf::train
