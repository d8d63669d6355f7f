#pragma once
// Pixels → rays, nerfstudio camera conventions: camera-to-world matrices in the OpenGL convention
// (x right, y up, the camera looks along −z), pixel centres at (col + 0.5, row + 0.5), OPENCV
// intrinsics (fx, fy, cx, cy; radial k1, k2, k3 and tangential p1, p2 distortion), unit
// directions.
// Distortion is removed in OpenCV's own image frame (y down) before the y flip; nerfstudio applies
// its undistortion to the already y-flipped coordinate, which is the same for k1, k2, k3 but
// flips the sign of p1. (The simulator's and SoundSpaces' cameras have no distortion.)
#include <torch/types.h>

#include "neraf/data/image_set.h"

namespace neraf::nerf {

struct RayBundle {
  torch::Tensor origins;         // [R, 3]
  torch::Tensor directions;      // [R, 3] unit
  torch::Tensor camera_indices;  // [R] int64: training image (appearance, pose correction); −1 none
  torch::Tensor nears;           // [R]
  torch::Tensor fars;            // [R]

  int64_t size() const { return origins.size(0); }
  RayBundle slice(int64_t begin, int64_t end) const;
};

// Per-camera intrinsics as a tensor row: [fx, fy, cx, cy, k1, k2, k3, p1, p2].
torch::Tensor intrinsics_row(const data::Intrinsics& k);  // [9] float32
constexpr int64_t kIntrinsicsRow = 9;

// Undistorts normalised OpenCV image coordinates (x right, y down): solves
// distort(x) = xd with Newton's method (10 iterations, analytic 2×2 Jacobian).
// xd: [N, 2]; dist: [N, 5] (k1, k2, k3, p1, p2) → [N, 2].
torch::Tensor undistort_opencv(const torch::Tensor& xd, const torch::Tensor& dist);
// The forward model (for tests): [N, 2] undistorted → distorted.
torch::Tensor distort_opencv(const torch::Tensor& x, const torch::Tensor& dist);

// Rays through pixel positions (px, py) in pixels (use col + 0.5, row + 0.5 for centres).
// c2w: [N, 3, 4]; intr: [N, 9] rows as intrinsics_row; px, py: [N]. Returns origins and unit
// directions; camera_indices, nears and fars are left for the caller.
RayBundle rays_from_pixels(const torch::Tensor& c2w, const torch::Tensor& intr,
                           const torch::Tensor& px, const torch::Tensor& py);

// All pixels of one camera in row-major order: H·W rays. c2w: [3, 4].
RayBundle camera_rays(const torch::Tensor& c2w, const data::Intrinsics& k);

}  // namespace neraf::nerf
