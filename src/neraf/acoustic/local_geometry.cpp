#include "neraf/acoustic/local_geometry.h"

#include <torch/torch.h>

#include "neraf/nerf/contraction.h"

namespace neraf::acoustic {

torch::Tensor world_to_grid_input(const torch::Tensor& p_m, const WorldToField& w) {
  TORCH_CHECK(p_m.dim() == 2 && p_m.size(1) == 3, "world_to_grid_input: expected [B, 3], got ",
              p_m.sizes());
  const auto f64 = torch::TensorOptions().dtype(torch::kFloat64).device(p_m.device());
  const auto a =
      torch::tensor({w[0], w[1], w[2], w[4], w[5], w[6], w[8], w[9], w[10]}, f64).view({3, 3});
  const auto b = torch::tensor({w[3], w[7], w[11]}, f64);
  const auto p = torch::matmul(p_m.to(torch::kFloat64), a.t()) + b;  // [B, 3] normalised frame
  return ((nerf::scene_contract(p) + 2) / 4).to(torch::kFloat32);
}

torch::Tensor sample_volume(const torch::Tensor& volume, const torch::Tensor& u) {
  TORCH_CHECK(volume.dim() == 4, "sample_volume: volume must be [L, D, H, W], got ",
              volume.sizes());
  TORCH_CHECK(u.dim() == 2 && u.size(1) == 3, "sample_volume: u must be [N, 3], got ", u.sizes());
  // grid_sample's last axis is (W, H, D) = (z, y, x); align_corners = false puts −1 and 1 on the
  // outer faces of the border voxels, as u = 0 and 1 are.
  const auto g = (u.to(volume.scalar_type()).flip(1) * 2 - 1).view({1, -1, 1, 1, 3});
  const auto s =
      torch::grid_sampler(volume.unsqueeze(0), g, /*interpolation_mode=*/0,
                          /*padding_mode=*/1, /*align_corners=*/false);  // [1, L, N, 1, 1]
  return s.view({volume.size(0), -1}).t();                               // [N, L]
}

torch::Tensor strided_map_coordinates(const torch::Tensor& u, int64_t grid_resolution,
                                      int64_t map_resolution) {
  TORCH_CHECK(map_resolution == (grid_resolution + 1) / 2,
              "strided_map_coordinates: a stride-2 map of ", grid_resolution, " cells has ",
              (grid_resolution + 1) / 2, ", not ", map_resolution);
  return (u * static_cast<double>(grid_resolution) + 0.5) / static_cast<double>(2 * map_resolution);
}

torch::Tensor local_geometry_features(const torch::Tensor& volume, const torch::Tensor& mic_u,
                                      const torch::Tensor& src_u, int64_t segment_points) {
  TORCH_CHECK(segment_points >= 1, "local_geometry_features: segment_points must be >= 1");
  TORCH_CHECK(mic_u.sizes() == src_u.sizes(), "local_geometry_features: mic_u ", mic_u.sizes(),
              " and src_u ", src_u.sizes(), " differ");
  const int64_t b = mic_u.size(0), k = segment_points, l = volume.size(0);
  const auto opts = torch::TensorOptions().dtype(torch::kFloat32).device(mic_u.device());
  const auto t = (torch::arange(k, opts) + 0.5) / static_cast<double>(k);  // [K]
  const auto m = mic_u.to(torch::kFloat32), s = src_u.to(torch::kFloat32);
  const auto along = m.unsqueeze(1) + t.view({1, k, 1}) * (s - m).unsqueeze(1);  // [B, K, 3]
  const auto points = torch::cat({m, s, along.reshape({b * k, 3})});             // [2B + BK, 3]
  const auto f = sample_volume(volume, points);                                  // [2B + BK, L]
  const auto seg = f.slice(0, 2 * b).view({b, k, l});                            // [B, K, L]
  return torch::cat({f.slice(0, 0, b), f.slice(0, b, 2 * b), seg.mean(1), std::get<0>(seg.max(1))},
                    1);  // [B, 4L]
}

}  // namespace neraf::acoustic
