#pragma once
// Tiny synthetic posed-image sets for the run tests of infer, eval and train (no files): cameras
// on a circle of radius 1 looking at the origin, images with a smooth colour pattern that depends
// on the view.
#include <torch/torch.h>

#include <cmath>
#include <string>

#include "neraf/data/image_set.h"
#include "neraf/infer/train_config.h"

namespace neraf::infer::fixtures {

inline torch::Tensor look_at_origin(double angle, double height) {
  const double px = std::cos(angle), pz = std::sin(angle), py = height;
  // OpenGL camera: −z looks at the origin → z axis = position direction.
  auto z = torch::tensor({px, py, pz}, torch::kFloat64);
  z = z / z.norm();
  auto up = torch::tensor({0.0, 1.0, 0.0}, torch::kFloat64);
  auto x = torch::cross(up, z, 0);
  x = x / x.norm();
  auto y = torch::cross(z, x, 0);
  auto t = torch::tensor({px, py, pz}, torch::kFloat64);
  return torch::stack({x, y, z, t}, 1).to(torch::kFloat32);  // [3, 4]
}

inline data::ImageSplit make_split(int64_t n, int64_t size, double angle0, bool train) {
  data::ImageSplit s;
  std::vector<torch::Tensor> poses, images;
  for (int64_t i = 0; i < n; ++i) {
    const double a = angle0 + 2.0 * M_PI * i / n;
    poses.push_back(look_at_origin(a, 0.2));
    data::Intrinsics k;
    k.width = k.height = static_cast<int>(size);
    k.fx = k.fy = size * 1.2;
    k.cx = k.cy = size / 2.0;
    s.intrinsics.push_back(k);
    s.files.push_back((train ? "train_" : "eval_") + std::to_string(i) + ".png");
    s.appearance_ids.push_back(train ? i : -1);
    auto yy = torch::arange(size).to(torch::kFloat32).view({size, 1, 1}) / size;
    auto xx = torch::arange(size).to(torch::kFloat32).view({1, size, 1}) / size;
    auto c = torch::tensor({0.8f, 0.3f, 0.5f}).view({1, 1, 3});
    auto img = (0.5 + 0.4 * torch::sin(6.0 * xx + 3.0 * yy + a + c * 4)).clamp(0, 1);
    images.push_back((img * 255).round().to(torch::kUInt8));
  }
  s.camera_to_world = torch::stack(poses);
  s.images = torch::stack(images);
  return s;
}

inline data::ImageSet make_image_set(int64_t n_train = 2, int64_t size = 8) {
  data::ImageSet set;
  set.train = make_split(n_train, size, 0.0, true);
  set.eval = make_split(1, size, 0.5, false);
  set.world_transform =
      torch::cat({torch::eye(3, torch::kFloat64), torch::zeros({3, 1}, torch::kFloat64)}, 1);
  set.world_scale = 1.0;
  set.source = "synthetic";
  set.eval_mode = "filename";
  return set;
}

// A small, fast configuration for tests.
inline TrainConfig tiny_train_config() {
  TrainConfig c = train_preset("cpu");
  c.model.field.grid = {4, 2, 10, 16, 64};
  c.model.field.hidden_dim = 16;
  c.model.field.hidden_dim_color = 16;
  c.model.field.appearance_dim = 4;
  c.model.proposal_nets = {nerf::ProposalNetConfig{{3, 2, 8, 16, 32}, 2, 16},
                           nerf::ProposalNetConfig{{3, 2, 8, 16, 64}, 2, 16}};
  c.model.sampler.proposal_samples = {16, 8};
  c.model.sampler.nerf_samples = 8;
  c.model.sampler.far_plane = 4.0;
  c.model.camera_opt.mode = nerf::CameraOptMode::SO3xR3;
  c.model.precision = nerf::Precision::fp32;
  c.rays_per_batch = 64;
  c.steps = 10;
  c.save_every = 5;
  return c;
}

}  // namespace neraf::infer::fixtures
