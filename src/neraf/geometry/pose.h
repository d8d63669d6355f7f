#pragma once
// Headings, yaw quaternions and camera poses in the simulator's y-up world (see sim/scene.h).
//
// A heading (yaw) of θ degrees is the rotation R_y(θ) about +y applied to the forward direction −z:
//   forward(θ) = R_y(θ)·(0, 0, −1) = (−sin θ, 0, −cos θ),   left(θ) = forward(θ + 90°).
// R_y(θ) as a quaternion (real LAST, scipy/RAF order) is (0, sin(θ/2), 0, cos(θ/2)); its
// scipy `as_euler('yxz')[0]` is θ again (wrapped to (−180°, 180°]).
#include <array>
#include <cmath>

#include "neraf/geometry/vec.h"

namespace neraf::geometry {

// R_y(angle) applied to v (right-handed rotation about +y).
inline Vec3 rotate_y(Vec3 v, double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return {c * v.x + s * v.z, v.y, -s * v.x + c * v.z};
}

inline Vec3 heading_forward(double yaw_deg) {
  const double a = deg_to_rad(yaw_deg);
  return {-std::sin(a), 0.0, -std::cos(a)};
}
inline Vec3 heading_left(double yaw_deg) { return heading_forward(yaw_deg + 90.0); }

struct Quaternion {  // unit quaternion, stored real LAST like scipy's as_quat() and RAF's
                     // tx_pos.txt
  double x = 0, y = 0, z = 0, w = 1;
};

inline Quaternion quaternion_from_yaw(double yaw_deg) {
  const double h = 0.5 * deg_to_rad(yaw_deg);
  return {0.0, std::sin(h), 0.0, std::cos(h)};
}

inline Vec3 rotate(const Quaternion& q, Vec3 v) {
  // v' = v + 2w(u×v) + 2u×(u×v), u = (x, y, z).
  const Vec3 u{q.x, q.y, q.z};
  const Vec3 t = 2.0 * cross(u, v);
  return v + q.w * t + cross(u, t);
}

// The heading of the rotated forward axis (−z), in degrees in (−180, 180]. For a pure rotation
// about +y this equals scipy's as_euler('yxz')[0].
inline double yaw_deg_from_quaternion(const Quaternion& q) {
  const Vec3 f = rotate(q, {0, 0, -1});
  return rad_to_deg(std::atan2(-f.x, -f.z));
}

// Camera-to-world pose in the nerfstudio / OpenGL convention: the camera looks along its local −z,
// x points right and y up in the image.
struct CameraPose {
  Vec3 right, up, back;  // world directions of the camera's local +x, +y, +z (columns of R)
  Vec3 position;

  Vec3 forward() const { return -back; }
  // Camera-frame direction → world direction.
  Vec3 to_world(Vec3 d) const { return d.x * right + d.y * up + d.z * back; }
  // 4×4 row-major camera-to-world matrix (last row 0 0 0 1), as written in transforms.json.
  std::array<std::array<double, 4>, 4> matrix() const {
    return {{{right.x, up.x, back.x, position.x},
             {right.y, up.y, back.y, position.y},
             {right.z, up.z, back.z, position.z},
             {0.0, 0.0, 0.0, 1.0}}};
  }
};

// A camera at `position` looking at `target` with world +y as "up" in the image. Looking straight
// up or down falls back to +x as the image's right axis.
inline CameraPose look_at(Vec3 position, Vec3 target) {
  CameraPose p;
  p.position = position;
  const Vec3 forward = normalized(target - position);
  Vec3 right = cross(forward, Vec3{0, 1, 0});
  right = norm(right) < 1e-9 ? Vec3{1, 0, 0} : normalized(right);
  p.right = right;
  p.up = normalized(cross(right, forward));
  p.back = -forward;
  return p;
}

}  // namespace neraf::geometry
