#include "neraf/sim/cameras.h"

#include <algorithm>
#include <cmath>

#include "neraf/sim/scene_json.h"
#include "neraf/sim/seeded_random.h"
#include "neraf/util/error.h"

namespace neraf::sim {

CameraIntrinsics camera_intrinsics(const Cameras& cameras) {
  CameraIntrinsics k;
  k.width = cameras.width;
  k.height = cameras.height;
  k.fx = k.fy = 0.5 * cameras.width / std::tan(0.5 * geometry::deg_to_rad(cameras.fov_deg));
  k.cx = 0.5 * cameras.width;
  k.cy = 0.5 * cameras.height;
  return k;
}

Vec3 pixel_ray_direction(const CameraView& view, double u, double v) {
  const auto& k = view.intrinsics;
  return normalized(view.pose.to_world({(u - k.cx) / k.fx, -(v - k.cy) / k.fy, -1.0}));
}

std::vector<CameraView> place_cameras(const Scene& scene, int count, uint64_t seed) {
  SeededRandom rng(seed);
  const auto& cam = scene.cameras;
  const double m = std::max(cam.wall_margin_m, kSurfaceClearanceM);
  const double w = scene.size.x - 2 * m, d = scene.size.z - 2 * m;  // the loop's rectangle
  const double perimeter = 2 * (w + d);
  const Vec3 centre = scene.size * 0.5;
  const CameraIntrinsics k = camera_intrinsics(cam);

  std::vector<CameraView> out;
  out.reserve(std::max(count, 0));
  int64_t tries = 0;
  while (static_cast<int>(out.size()) < count) {
    if (++tries > 1000 * int64_t(count) + 1000)
      throw Error("cameras: could not place " + std::to_string(count) +
                  " cameras near the walls outside the furniture; reduce cameras.wall_margin_m or "
                  "move furniture away from the walls");
    // Walk s metres along the loop x0 → x1 (at z = m), then up z, back along x, down z.
    double s = rng.uniform(0, perimeter);
    Vec3 p{0, rng.uniform(cam.min_height_m, cam.max_height_m), 0};
    if (s < w) {
      p.x = m + s, p.z = m;
    } else if ((s -= w) < d) {
      p.x = m + w, p.z = m + s;
    } else if ((s -= d) < w) {
      p.x = m + w - s, p.z = m + d;
    } else {
      s -= w;
      p.x = m, p.z = m + d - s;
    }
    Vec3 target = centre + Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)} *
                               cam.look_jitter_m;
    for (int a = 0; a < 3; ++a) {
      target[a] = std::clamp(target[a], kSurfaceClearanceM, scene.size[a] - kSurfaceClearanceM);
    }
    if (furniture_containing(scene, p, 0.1) >= 0) continue;
    if (norm(target - p) < 0.25) continue;  // degenerate view direction
    out.push_back({geometry::look_at(p, target), k});
  }
  return out;
}

}  // namespace neraf::sim
