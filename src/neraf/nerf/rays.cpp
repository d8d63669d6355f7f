#include "neraf/nerf/rays.h"

#include <torch/torch.h>

namespace neraf::nerf {

RayBundle RayBundle::slice(int64_t begin, int64_t end) const {
  auto s = [&](const torch::Tensor& t) { return t.defined() ? t.slice(0, begin, end) : t; };
  return {s(origins), s(directions), s(camera_indices), s(nears), s(fars)};
}

torch::Tensor intrinsics_row(const data::Intrinsics& k) {
  return torch::tensor({k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.k3, k.p1, k.p2}, torch::kFloat64)
      .to(torch::kFloat32);
}

torch::Tensor distort_opencv(const torch::Tensor& x, const torch::Tensor& dist) {
  const auto u = x.select(1, 0), v = x.select(1, 1);
  const auto k1 = dist.select(1, 0), k2 = dist.select(1, 1), k3 = dist.select(1, 2);
  const auto p1 = dist.select(1, 3), p2 = dist.select(1, 4);
  const auto r2 = u * u + v * v;
  const auto radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const auto xd = u * radial + 2.0 * p1 * u * v + p2 * (r2 + 2.0 * u * u);
  const auto yd = v * radial + p1 * (r2 + 2.0 * v * v) + 2.0 * p2 * u * v;
  return torch::stack({xd, yd}, 1);
}

torch::Tensor undistort_opencv(const torch::Tensor& xd, const torch::Tensor& dist) {
  const auto k1 = dist.select(1, 0), k2 = dist.select(1, 1), k3 = dist.select(1, 2);
  const auto p1 = dist.select(1, 3), p2 = dist.select(1, 4);
  const auto xd0 = xd.select(1, 0), yd0 = xd.select(1, 1);
  torch::Tensor u = xd0.clone(), v = yd0.clone();
  for (int it = 0; it < 10; ++it) {
    const auto r2 = u * u + v * v;
    const auto radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const auto fx = u * radial + 2.0 * p1 * u * v + p2 * (r2 + 2.0 * u * u) - xd0;
    const auto fy = v * radial + p1 * (r2 + 2.0 * v * v) + 2.0 * p2 * u * v - yd0;
    // d radial / du = 2u (k1 + 2 k2 r2 + 3 k3 r2²), likewise for v.
    const auto dr = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    const auto fx_u = radial + 2.0 * u * u * dr + 2.0 * p1 * v + 6.0 * p2 * u;
    const auto fx_v = 2.0 * u * v * dr + 2.0 * p1 * u + 2.0 * p2 * v;
    const auto fy_u = 2.0 * u * v * dr + 2.0 * p1 * u + 2.0 * p2 * v;
    const auto fy_v = radial + 2.0 * v * v * dr + 6.0 * p1 * v + 2.0 * p2 * u;
    const auto det = fx_u * fy_v - fx_v * fy_u;
    const auto safe = torch::where(det.abs() < 1e-12, torch::ones_like(det), det);
    const auto step_u = (fx * fy_v - fy * fx_v) / safe;
    const auto step_v = (fy * fx_u - fx * fy_u) / safe;
    u = torch::where(det.abs() < 1e-12, u, u - step_u);
    v = torch::where(det.abs() < 1e-12, v, v - step_v);
  }
  return torch::stack({u, v}, 1);
}

RayBundle rays_from_pixels(const torch::Tensor& c2w, const torch::Tensor& intr,
                           const torch::Tensor& px, const torch::Tensor& py) {
  const auto fx = intr.select(1, 0), fy = intr.select(1, 1);
  const auto cx = intr.select(1, 2), cy = intr.select(1, 3);
  torch::Tensor xn = (px - cx) / fx;  // OpenCV normalised coordinates (y down)
  torch::Tensor yn = (py - cy) / fy;
  const torch::Tensor dist = intr.slice(1, 4, 9);
  // Only pay for the Newton iterations when some camera is distorted (host check, cheap).
  if (dist.abs().max().item<double>() > 0) {
    const torch::Tensor und = undistort_opencv(torch::stack({xn, yn}, 1), dist);
    xn = und.select(1, 0);
    yn = und.select(1, 1);
  }
  // OpenGL camera frame: x right, y up, looking along −z.
  const torch::Tensor d_cam = torch::stack({xn, -yn, -torch::ones_like(xn)}, 1);  // [N, 3]
  const torch::Tensor rot = c2w.slice(2, 0, 3);                                   // [N, 3, 3]
  torch::Tensor d = torch::bmm(rot, d_cam.unsqueeze(2)).squeeze(2);
  d = d / d.norm(2, 1, /*keepdim=*/true);
  return {c2w.select(2, 3).contiguous(), d, torch::Tensor(), torch::Tensor(), torch::Tensor()};
}

RayBundle camera_rays(const torch::Tensor& c2w, const data::Intrinsics& k) {
  const auto dev = c2w.device();
  const auto opts = torch::TensorOptions().dtype(torch::kFloat32).device(dev);
  const int64_t H = k.height, W = k.width;
  const torch::Tensor rows = torch::arange(H, opts) + 0.5;
  const torch::Tensor cols = torch::arange(W, opts) + 0.5;
  const torch::Tensor py = rows.unsqueeze(1).expand({H, W}).reshape({-1});
  const torch::Tensor px = cols.unsqueeze(0).expand({H, W}).reshape({-1});
  const torch::Tensor cam = c2w.to(opts).unsqueeze(0).expand({H * W, 3, 4});
  const torch::Tensor intr = intrinsics_row(k).to(dev).unsqueeze(0).expand({H * W, kIntrinsicsRow});
  return rays_from_pixels(cam, intr, px, py);
}

}  // namespace neraf::nerf
