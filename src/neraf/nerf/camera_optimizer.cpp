#include "neraf/nerf/camera_optimizer.h"

#include <torch/torch.h>

namespace neraf::nerf {

torch::Tensor exp_map_so3xr3(const torch::Tensor& tangent) {
  const int64_t N = tangent.size(0);
  const torch::Tensor w = tangent.slice(1, 3, 6);                       // [N, 3]
  const torch::Tensor angle = (w * w).sum(1).clamp_min(1e-4).sqrt();    // [N]
  const torch::Tensor fac1 = (torch::sin(angle) / angle).view({N, 1, 1});
  const torch::Tensor fac2 = ((1.0 - torch::cos(angle)) / (angle * angle)).view({N, 1, 1});
  const torch::Tensor zero = torch::zeros({N}, tangent.options());
  const auto wx = w.select(1, 0), wy = w.select(1, 1), wz = w.select(1, 2);
  const torch::Tensor skew =
      torch::stack({zero, -wz, wy, wz, zero, -wx, -wy, wx, zero}, 1).view({N, 3, 3});
  const torch::Tensor rot = torch::eye(3, tangent.options()).unsqueeze(0) + fac1 * skew +
                            fac2 * torch::bmm(skew, skew);
  return torch::cat({rot, tangent.slice(1, 0, 3).unsqueeze(2)}, 2);  // [N, 3, 4]
}

CameraOptimizerImpl::CameraOptimizerImpl(const CameraOptConfig& config, int64_t num_cameras)
    : config_(config) {
  if (enabled())
    pose_adjustment =
        register_parameter("pose_adjustment", torch::zeros({num_cameras, 6}, torch::kFloat32));
}

torch::Tensor CameraOptimizerImpl::corrections(const torch::Tensor& camera_indices) {
  TORCH_CHECK(enabled(), "camera optimizer is off");
  return exp_map_so3xr3(pose_adjustment.index_select(0, camera_indices));
}

RayBundle CameraOptimizerImpl::apply(const RayBundle& rays) {
  if (!enabled()) return rays;
  const torch::Tensor valid = (rays.camera_indices >= 0).unsqueeze(1);         // [R, 1]
  const torch::Tensor c = corrections(rays.camera_indices.clamp_min(0));       // [R, 3, 4]
  RayBundle out = rays;
  out.origins = torch::where(valid, rays.origins + c.select(2, 3), rays.origins);
  const torch::Tensor d =
      torch::bmm(c.slice(2, 0, 3), rays.directions.unsqueeze(2)).squeeze(2);  // [R, 3]
  out.directions = torch::where(valid, d, rays.directions);
  return out;
}

torch::Tensor CameraOptimizerImpl::regularizer() {
  if (!enabled()) return torch::zeros({});
  return pose_adjustment.slice(1, 0, 3).norm(2, 1).mean() * config_.trans_l2_penalty +
         pose_adjustment.slice(1, 3, 6).norm(2, 1).mean() * config_.rot_l2_penalty;
}

}  // namespace neraf::nerf
