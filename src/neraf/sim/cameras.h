#pragma once
// Pinhole cameras of the simulated photos: intrinsics (nerfstudio OPENCV model without distortion)
// and poses placed like NeRAF's SoundSpaces views (near the walls, looking into the room).
#include <cstdint>
#include <vector>

#include "neraf/geometry/pose.h"
#include "neraf/sim/scene.h"

namespace neraf::sim {

struct CameraIntrinsics {  // pixels; square pixels, principal point at the image centre
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

struct CameraView {
  geometry::CameraPose pose;  // camera-to-world, OpenGL convention (looks along local −z)
  CameraIntrinsics intrinsics;
};

// fx = fy = (width / 2) / tan(fov_deg / 2) (fov is horizontal), cx = width / 2, cy = height / 2.
CameraIntrinsics camera_intrinsics(const Cameras& cameras);

// Unit world direction of the ray through image point (u, v) in pixels (u right, v down; the
// centre of pixel (i, j) is (i + 0.5, j + 0.5), as nerfstudio generates rays):
// camera-frame direction ((u − cx)/fx, −(v − cy)/fy, −1).
Vec3 pixel_ray_direction(const CameraView& view, double u, double v);

// `count` cameras, deterministic for `seed`: each at a uniformly random point of the loop that runs
// wall_margin_m inside the walls, at a uniform height in [min_height_m, max_height_m], looking at
// the room centre plus a uniform offset in [−look_jitter_m, look_jitter_m]³ (kept inside the room).
// Positions inside (or within 0.1 m of) furniture are redrawn.
std::vector<CameraView> place_cameras(const Scene& scene, int count, uint64_t seed);

}  // namespace neraf::sim
