#pragma once
// Per-training-camera pose refinement (nerfstudio CameraOptimizer, mode SO3xR3): a [num_cams, 6]
// tangent vector (translation, axis-angle rotation) initialised to zero, mapped to a 3×4 [R|t]
// correction that moves ray origins (o + t) and rotates directions (R d). Applied in training only.
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include "neraf/nerf/config.h"
#include "neraf/nerf/rays.h"

namespace neraf::nerf {

// Exponential map of SO3×R3: tangent [N, 6] = (t, ω) → [N, 3, 4] = [Rodrigues(ω) | t]. The squared
// angle is clamped at 1e-4 before the square root (as nerfstudio), so ω = 0 gives exactly the
// identity with finite gradients.
torch::Tensor exp_map_so3xr3(const torch::Tensor& tangent);

class CameraOptimizerImpl : public torch::nn::Module {
 public:
  CameraOptimizerImpl(const CameraOptConfig& config, int64_t num_cameras);

  bool enabled() const { return config_.mode != CameraOptMode::off; }
  // [R, 3, 4] corrections for camera indices [R] (must be ≥ 0).
  torch::Tensor corrections(const torch::Tensor& camera_indices);
  // o ← o + t, d ← R d for rays with camera_indices ≥ 0 (a no-op when disabled).
  RayBundle apply(const RayBundle& rays);
  // trans_l2_penalty · mean‖t‖ + rot_l2_penalty · mean‖ω‖ (0 when disabled).
  torch::Tensor regularizer();

  torch::Tensor pose_adjustment;  // [num_cameras, 6] (only registered when enabled)

 private:
  CameraOptConfig config_;
};
TORCH_MODULE(CameraOptimizer);

}  // namespace neraf::nerf
