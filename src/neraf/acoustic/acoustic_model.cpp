#include "neraf/acoustic/acoustic_model.h"

#include <torch/torch.h>

#include "neraf/util/error.h"

namespace neraf::acoustic {

GridMode parse_grid_mode(const std::string& name) {
  if (name == "sampled") return GridMode::kSampled;
  if (name == "zeros") return GridMode::kZeros;
  if (name == "none") return GridMode::kNone;
  throw Error("acoustic grid_mode: unknown value '" + name + "': use sampled, zeros or none");
}

std::string to_string(GridMode mode) {
  switch (mode) {
    case GridMode::kSampled:
      return "sampled";
    case GridMode::kZeros:
      return "zeros";
    case GridMode::kNone:
      return "none";
  }
  return "sampled";
}

GridFeatures parse_grid_features(const std::string& name) {
  if (name == "global") return GridFeatures::kGlobal;
  if (name == "local") return GridFeatures::kLocal;
  if (name == "both") return GridFeatures::kBoth;
  throw Error("acoustic grid_features: unknown value '" + name + "': use global, local or both");
}

std::string to_string(GridFeatures features) {
  switch (features) {
    case GridFeatures::kGlobal:
      return "global";
    case GridFeatures::kLocal:
      return "local";
    case GridFeatures::kBoth:
      return "both";
  }
  return "global";
}

AcousticModelOptions acoustic_preset(const std::string& name, int64_t n_channels, int64_t n_freq,
                                     int64_t max_len) {
  AcousticModelOptions o;
  o.max_len = max_len;
  if (name == "paper" || name == "reference") {
    o.grid.resolution = 128;
    o.grid.cells_per_update = 4096;
    o.resnet = resnet3d_paper_options();
    o.nacf = nacf_paper_options(n_channels, n_freq, resnet3d_out_features(o.resnet));
    if (name == "reference") {  // the published model exactly: its 18 vectors, its BatchNorm
      o.grid.view_directions = ViewDirections::kReference;
      o.resnet.running_stats = true;
    }
  } else if (name == "cpu") {
    o.grid.resolution = 32;
    // 1024 cells × 18 directions = 18,432 radiance-field queries with autograd per step (the
    // paper's 4096 would add ~74k field samples, more than the vision batch itself on 2 cores);
    // a full sweep of the 32³ grid still takes only 32 steps (paper: 512 steps for 128³).
    o.grid.cells_per_update = 1024;
    o.resnet = resnet3d_cpu_options();
    o.nacf = nacf_cpu_options(n_channels, n_freq, resnet3d_out_features(o.resnet));
    o.nacf.bf16 = true;               // training follows --precision (infer::audio_model_options)
    o.nacf.relative_geometry = true;  // box from the data (infer::audio_model_options)
    o.nacf.position_max_freq_exp = 1.0;  // room-scale positions (train_config.cpp says why)
  } else {
    throw Error("preset: unknown acoustic preset '" + name + "': use cpu, paper or reference");
  }
  return o;
}

AcousticModelImpl::AcousticModelImpl(AcousticModelOptions options) : options_(std::move(options)) {
  require(options_.max_len >= 2, "audio max_len: must be at least 2 frames");
  require(options_.segment_points >= 1, "acoustic segment_points: must be at least 1");
  const bool local = options_.grid_features != GridFeatures::kGlobal;
  if (options_.grid_mode == GridMode::kNone) {
    require(!local, "acoustic grid_features " + to_string(options_.grid_features) +
                        ": needs a grid (grid mode none has none)");
    options_.nacf.grid_features = 0;
    options_.nacf.local_features = 0;
  } else {
    resnet3d_ = register_module("resnet3d", ResNet3d(options_.resnet));
    options_.nacf.grid_features =
        options_.grid_features == GridFeatures::kLocal ? 0 : resnet3d_->out_features();
    // At the mic, at the source, mean and max along the segment (local_geometry.h).
    options_.nacf.local_features = local ? 4 * options_.resnet.stem_channels : 0;
  }
  field_ = register_module("field", Nacf(options_.nacf));
}

SceneFeatures AcousticModelImpl::scene_features(const torch::Tensor& grid) {
  if (options_.grid_mode == GridMode::kNone) return {};
  const int64_t s = options_.grid.resolution;
  torch::Tensor input;
  if (options_.grid_mode == GridMode::kZeros) {
    const auto device = resnet3d_->parameters().front().device();
    input = torch::zeros({1, options_.resnet.in_channels, s, s, s},
                         torch::dtype(torch::kFloat32).device(device));
  } else {
    TORCH_CHECK(grid.defined() && grid.dim() == 4 && grid.size(0) == options_.resnet.in_channels,
                "AcousticModel: grid must be [", options_.resnet.in_channels, ", S, S, S]");
    input = grid.unsqueeze(0);
  }
  if (options_.grid_features == GridFeatures::kGlobal)
    return {resnet3d_->forward(input).squeeze(0), {}};  // [G]
  if (options_.grid_features == GridFeatures::kLocal)
    return {{}, resnet3d_->stem(input).squeeze(0)};  // [L, S', S', S']; the rest is unused
  auto [stem, pooled] = resnet3d_->forward_with_stem(input);
  return {pooled.squeeze(0), stem.squeeze(0)};  // [G], [L, S', S', S']
}

torch::Tensor AcousticModelImpl::nacf_input(const SceneFeatures& features, const NacfOptions& scene,
                                            const torch::Tensor& t, const torch::Tensor& mic_m,
                                            const torch::Tensor& src_m,
                                            const torch::Tensor& rot) const {
  torch::Tensor local;
  if (options_.nacf.local_features > 0) {
    TORCH_CHECK(features.volume.defined(),
                "AcousticModel: per-query grid features need the "
                "stem map (scene_features of this model)");
    // The grid's cube → the stem map's frame (its conv1 has stride 2, padding kernel/2).
    auto stem_frame = [&](const torch::Tensor& p_m) {
      return strided_map_coordinates(world_to_grid_input(p_m, scene.world_to_field),
                                     options_.grid.resolution, features.volume.size(1));
    };
    local = local_geometry_features(features.volume, stem_frame(mic_m), stem_frame(src_m),
                                    options_.segment_points);  // [B, 4L]
  }
  return acoustic::nacf_input(scene, features.global, t, options_.max_len, mic_m, src_m, rot,
                              local);
}

torch::Tensor AcousticModelImpl::forward_with_feature(const SceneFeatures& features,
                                                      const torch::Tensor& t,
                                                      const torch::Tensor& mic_m,
                                                      const torch::Tensor& src_m,
                                                      const torch::Tensor& rot) const {
  return field_->forward(nacf_input(features, options_.nacf, t, mic_m, src_m, rot));  // [B, C, F]
}

torch::Tensor AcousticModelImpl::forward(const torch::Tensor& grid, const torch::Tensor& t,
                                         const torch::Tensor& mic_m, const torch::Tensor& src_m,
                                         const torch::Tensor& rot) {
  return forward_with_feature(scene_features(grid), t, mic_m, src_m, rot);
}

namespace {

// Restores a module's train/eval flag on scope exit.
class EvalScope {
 public:
  explicit EvalScope(torch::nn::Module& m) : m_(m), was_training_(m.is_training()) { m_.eval(); }
  ~EvalScope() { m_.train(was_training_); }
  EvalScope(const EvalScope&) = delete;
  EvalScope& operator=(const EvalScope&) = delete;

 private:
  torch::nn::Module& m_;
  bool was_training_;
};

torch::Tensor pose_row(const torch::Tensor& x, const char* name) {
  TORCH_CHECK(x.numel() == 3, "render_stft: ", name, " must have 3 values, got ", x.sizes());
  return x.reshape({1, 3});
}

}  // namespace

torch::Tensor AcousticModelImpl::render_stft_with_feature(const SceneFeatures& features,
                                                          const torch::Tensor& mic_m,
                                                          const torch::Tensor& src_m,
                                                          const torch::Tensor& rot) const {
  torch::NoGradGuard no_grad;  // thread-local; NAcF needs no eval mode (no BatchNorm or dropout)
  const int64_t n = options_.max_len;
  const auto device = field_->parameters().front().device();
  const auto t = torch::arange(n, torch::dtype(torch::kInt64).device(device));
  const auto mic = pose_row(mic_m, "mic").expand({n, 3});
  const auto src = pose_row(src_m, "source").expand({n, 3});
  const auto r = pose_row(rot, "rot").expand({n, 3});
  const auto out = forward_with_feature(features, t, mic, src, r);  // [T, C, F]
  return out.permute({1, 2, 0}).contiguous();                       // [C, F, T]
}

torch::Tensor AcousticModelImpl::render_stft(const torch::Tensor& grid, const torch::Tensor& mic_m,
                                             const torch::Tensor& src_m, const torch::Tensor& rot) {
  torch::NoGradGuard no_grad;
  EvalScope eval(*this);
  return render_stft_with_feature(scene_features(grid), mic_m, src_m, rot);
}

}  // namespace neraf::acoustic
