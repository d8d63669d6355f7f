#pragma once
// Exported models (MODEL.nrf, the neraf_rt runtime's file; format in runtime/model_file.h).
//
//   neraf export --run RUN --out MODEL.nrf       export_model(load_audio_run(RUN), path, options)
//   neraf render rir --model MODEL.nrf ...       load_exported_model(path).predict_log_stft_batch
//
// Exporting folds the constant scene feature into NAcF's first layer (W₁·[g, x] + b₁ =
// W₁ₓ·x + (b₁ + W₁g·g)): the file needs no grid, no ResNet3D and no radiance field. Queries of
// an ExportedModel run through neraf_rt's C API (float32), the path an engine takes.
#include <torch/torch.h>

#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "neraf/infer/audio_field.h"
#include "neraf/infer/audio_run.h"
#include "neraf/runtime/model_file.h"

struct neraf_model;

namespace neraf::infer {

struct ExportOptions {
  bool bf16 = false;  // store the weights as bfloat16 (half the file; the runtime widens them)
};

// The runtime's description of `run`'s acoustic field (torch tensors copied out, feature folded).
rt::ModelData export_model_data(const AudioRun& run, const ExportOptions& options = {});

struct ExportReport {
  int64_t file_bytes = 0;
  double max_abs_difference = 0;  // |runtime − LibTorch| of the log-STFT over the checked poses
  int64_t poses_checked = 0;
};

// Writes MODEL.nrf atomically, then loads it back through neraf_rt and compares its predictions
// with `run`'s (float32) at `check_poses` poses spread over the training box (half of them with
// the source over the box grown by half its size on each side, mostly outside); neraf::Error (and
// no file) when they differ by more than 1e-3 (fp32) or 0.25 (bf16) in log-magnitude.
ExportReport export_model(const AudioRun& run, const std::string& path,
                          const ExportOptions& options = {}, int64_t check_poses = 8);

// A loaded MODEL.nrf (immutable; queries are const and thread-safe).
class ExportedModel final : public AudioField {
 public:
  const AudioRunInfo& info() const override { return info_; }
  torch::Tensor predict_log_stft_batch(const torch::Tensor& mic, const torch::Tensor& src,
                                       const torch::Tensor& yaw_deg) const override;
  // The file's metadata: "run", "checkpoint", "step", "preset", "modality", "grid",
  // "data" (the run's RUN/data.json), "seed", "audio_fraction".
  const nlohmann::json& metadata() const { return metadata_; }
  const std::string& path() const { return path_; }
  // Positions outside the training box are refused (neraf::Error) unless allowed.
  void allow_outside(bool allow) { allow_outside_ = allow; }

 private:
  friend ExportedModel load_exported_model(const std::string& path);
  std::string path_;
  AudioRunInfo info_;
  nlohmann::json metadata_;
  std::shared_ptr<neraf_model> model_;
  bool allow_outside_ = true;
};

// neraf::Error naming the file for a missing, truncated, foreign or newer-version file.
ExportedModel load_exported_model(const std::string& path);

}  // namespace neraf::infer
