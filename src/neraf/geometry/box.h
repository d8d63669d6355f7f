#pragma once
// Boxes rotated about +y (furniture), in the y-up world of sim/scene.h: point tests, world
// bounds and ray intersection. Local frame: box-aligned axes, origin at the centre; world =
// centre + R_y(yaw)·local.
#include <algorithm>
#include <cmath>
#include <limits>

#include "neraf/geometry/pose.h"
#include "neraf/geometry/vec.h"

namespace neraf::geometry {

struct YawBox {
  Vec3 center;
  Vec3 half;           // half extents along the local axes (all > 0)
  double yaw_rad = 0;  // rotation about +y

  Vec3 to_local(Vec3 p) const { return rotate_y(p - center, -yaw_rad); }
  Vec3 dir_to_local(Vec3 d) const { return rotate_y(d, -yaw_rad); }
  Vec3 dir_to_world(Vec3 d) const { return rotate_y(d, yaw_rad); }

  // True when p lies inside the box grown by `clearance` on every side.
  bool contains(Vec3 p, double clearance = 0.0) const {
    const Vec3 l = to_local(p);
    return std::abs(l.x) < half.x + clearance && std::abs(l.y) < half.y + clearance &&
           std::abs(l.z) < half.z + clearance;
  }

  // Half extents of the world-axis-aligned bounding box.
  Vec3 world_half_extent() const {
    const double c = std::abs(std::cos(yaw_rad)), s = std::abs(std::sin(yaw_rad));
    return {c * half.x + s * half.z, half.y, s * half.x + c * half.z};
  }
};

struct BoxHit {
  double t = std::numeric_limits<double>::infinity();  // ray parameter of the entry point
  Vec3 normal_local;                                   // outward normal of the entered face
  int axis = -1;                                       // local axis of that face (0, 1, 2)
};

// Ray (origin o, direction d, not necessarily unit) against the box from OUTSIDE: the entry point
// with t in (t_min, t_max). Returns false when the ray misses or starts inside.
inline bool intersect(const YawBox& box, Vec3 o, Vec3 d, double t_min, double t_max, BoxHit* hit) {
  const Vec3 lo = box.to_local(o), ld = box.dir_to_local(d);
  double t0 = -std::numeric_limits<double>::infinity(),
         t1 = std::numeric_limits<double>::infinity();
  int axis = -1;
  double sign = 0;
  for (int a = 0; a < 3; ++a) {
    const double h = box.half[a];
    if (std::abs(ld[a]) < 1e-300) {
      if (std::abs(lo[a]) > h) return false;
      continue;
    }
    const double inv = 1.0 / ld[a];
    double tn = (-h - lo[a]) * inv, tf = (h - lo[a]) * inv;
    double s = -1.0;  // entering through the −h face
    if (tn > tf) {
      std::swap(tn, tf);
      s = 1.0;
    }
    if (tn > t0) {
      t0 = tn;
      axis = a;
      sign = s;
    }
    t1 = std::min(t1, tf);
  }
  if (axis < 0 || t0 > t1 || t0 <= t_min || t0 >= t_max) return false;
  if (hit) {
    hit->t = t0;
    hit->axis = axis;
    Vec3 n{0, 0, 0};
    n[axis] = sign;
    hit->normal_local = n;
  }
  return true;
}

}  // namespace neraf::geometry
