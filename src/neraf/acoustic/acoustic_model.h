#pragma once
// The acoustic branch without its data: ResNet3D scene encoder + encoders + NAcF
// (neraf-reference.md §1.1, §1.6). The voxel grid itself lives in GridSampler (owned by the
// trainer, which also owns the radiance field that fills it); this module only reads it.
//
// Grid modes (the paper's ablations):
//   kSampled  the 7×S³ grid → ResNet3D → scene feature (the reference, default)
//   kZeros    an all-zero 7×S³ grid (all 7 channels) through the same ResNet3D: no scene
//             information, same network
//   kNone     no ResNet3D; NAcF takes the no-grid input order [mic, source, time, rot] (163)
//
// Grid features (how the encoded grid reaches NAcF; kSampled and kZeros):
//   kGlobal   the pooled feature, one vector per room (the published design, default)
//   kLocal    geometry per query instead: ResNet3D's stem map (before the max pool, ⌈S/2⌉³)
//             read at the microphone, at the source and along the segment between them
//             (local_geometry.h), 4 × stem channels per query; NAcF's input in the no-grid
//             order with these appended (ResNet3D's later stages are then not run)
//   kBoth     both: the pooled feature and the per-query features
//
// Presets (acoustic_preset): "paper" = grid 128³, ResNet3D-50/layer3 (1024 features), NAcF
// 1187→5096→2048→1024→1024→512, 4096 cells per grid update; "cpu" = grid 32³ with 1024 cells per
// update, small BasicBlock ResNet3D (256 features), NAcF 5×512 (the paper's text) with the
// relative-geometry inputs (nacf.h), bf16 trunk matrix products; "reference" = "paper" with the
// published grid sampler's 18 viewing directions and ResNet3D's BatchNorm with running statistics
// (the published model exactly; paper keeps our spread directions and per-grid statistics).
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include <cstdint>
#include <string>

#include "neraf/acoustic/grid_sampler.h"
#include "neraf/acoustic/nacf.h"
#include "neraf/acoustic/resnet3d.h"

namespace neraf::acoustic {

enum class GridMode { kSampled, kZeros, kNone };
GridMode parse_grid_mode(const std::string& name);  // "sampled" | "zeros" | "none"
std::string to_string(GridMode mode);

enum class GridFeatures { kGlobal, kLocal, kBoth };
GridFeatures parse_grid_features(const std::string& name);  // "global" | "local" | "both"
std::string to_string(GridFeatures features);

// What NAcF reads of one room's encoded grid.
struct SceneFeatures {
  torch::Tensor global;  // [G] pooled ResNet3D feature; undefined for kNone and kLocal
  torch::Tensor volume;  // [L, S', S', S'] ResNet3D's stem map; undefined for kGlobal and kNone
};

struct AcousticModelOptions {
  GridSamplerOptions grid;
  ResNet3dOptions resnet = resnet3d_cpu_options();
  // grid_features and local_features are set from resnet by the model; the box and the world
  // map from the data (infer::audio_model_options).
  NacfOptions nacf = nacf_cpu_options(2, 257);
  GridMode grid_mode = GridMode::kSampled;
  GridFeatures grid_features = GridFeatures::kGlobal;
  int64_t segment_points = 8;  // points read inside the mic–source segment (kLocal, kBoth)
  int64_t max_len = 78;  // frames per RIR (time normalisation t/(max_len − 1)); set from the data
};

// name: "cpu" | "paper" | "reference"; n_channels C, n_freq F and max_len come from the dataset.
AcousticModelOptions acoustic_preset(const std::string& name, int64_t n_channels, int64_t n_freq,
                                     int64_t max_len);

class AcousticModelImpl : public torch::nn::Module {
 public:
  explicit AcousticModelImpl(AcousticModelOptions options);

  // What NAcF reads of the grid [7, S, S, S]: the pooled feature and/or the stem map, as the
  // grid features ask (kZeros: of an all-zero grid; `grid` may be undefined there; kNone: none).
  // Runs ResNet3D in the module's current mode.
  SceneFeatures scene_features(const torch::Tensor& grid);

  // grid: [7, S, S, S] (ignored for kZeros/kNone; may be undefined there); t: [B] int64 frame
  // indices; mic_m, src_m: [B, 3] positions in metres (float64 advised; normalised here by
  // options().nacf's box, nacf_input); rot: [B, 3] stored orientation.
  // → [B, C, F] predicted log-magnitudes. ResNet3D runs on every call (the reference re-runs it on
  // every audio step; its gradient reaches the freshly written grid cells).
  torch::Tensor forward(const torch::Tensor& grid, const torch::Tensor& t,
                        const torch::Tensor& mic_m, const torch::Tensor& src_m,
                        const torch::Tensor& rot);
  // NAcF's input [B, in_features] for positions of the room `scene` describes (its box and world
  // map; options().nacf for a one-scene model): nacf_input with the per-query features read
  // from features.volume when the model uses them.
  torch::Tensor nacf_input(const SceneFeatures& features, const NacfOptions& scene,
                           const torch::Tensor& t, const torch::Tensor& mic_m,
                           const torch::Tensor& src_m, const torch::Tensor& rot) const;
  // forward with precomputed scene features. Runs NAcF only, which has no BatchNorm or dropout:
  // the same in either mode, and reads no module state but the parameters.
  torch::Tensor forward_with_feature(const SceneFeatures& features, const torch::Tensor& t,
                                     const torch::Tensor& mic_m, const torch::Tensor& src_m,
                                     const torch::Tensor& rot) const;

  // All frames t = 0..max_len−1 of one pose (mic_m, src_m in metres, rot: [3] or [1, 3]) →
  // [C, F, T].
  // No autograd, ResNet3D and NAcF in eval mode (the previous mode is restored), one batch of T.
  torch::Tensor render_stft(const torch::Tensor& grid, const torch::Tensor& mic_m,
                            const torch::Tensor& src_m, const torch::Tensor& rot);
  // Same from scene features computed once (in eval mode) for many RIRs: the inference query.
  // NAcF only, so no train/eval switch is needed and none is made; with the thread-local
  // NoGradGuard it touches no shared state and may run from several threads at once.
  torch::Tensor render_stft_with_feature(const SceneFeatures& features, const torch::Tensor& mic_m,
                                         const torch::Tensor& src_m,
                                         const torch::Tensor& rot) const;

  const AcousticModelOptions& options() const { return options_; }
  // Null for GridMode::kNone.
  ResNet3d& resnet3d() { return resnet3d_; }
  Nacf& field() { return field_; }

 private:
  AcousticModelOptions options_;
  ResNet3d resnet3d_{nullptr};  // registered as "resnet3d"
  Nacf field_{nullptr};         // registered as "field"
};
TORCH_MODULE(AcousticModel);

}  // namespace neraf::acoustic
