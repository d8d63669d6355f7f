#include "neraf/geometry/quaternion.h"

#include <cmath>
#include <limits>

namespace neraf::geometry {

RotMat quaternion_to_matrix(const Quaternion& q_in) {
  const double n = std::sqrt(q_in.x * q_in.x + q_in.y * q_in.y + q_in.z * q_in.z + q_in.w * q_in.w);
  if (!(n > 0) || !std::isfinite(n)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {{{nan, nan, nan}, {nan, nan, nan}, {nan, nan, nan}}};
  }
  const double x = q_in.x / n, y = q_in.y / n, z = q_in.z / n, w = q_in.w / n;
  RotMat r;
  r[0] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)};
  r[1] = {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)};
  r[2] = {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)};
  return r;
}

Quaternion matrix_to_quaternion(const RotMat& r) {
  // Shepperd: pick the largest of w², x², y², z² to divide by, for numerical stability.
  const double trace = r[0][0] + r[1][1] + r[2][2];
  Quaternion q;
  if (trace >= r[0][0] && trace >= r[1][1] && trace >= r[2][2]) {
    const double s = 2 * std::sqrt(1 + trace);  // 4w
    q.w = s / 4;
    q.x = (r[2][1] - r[1][2]) / s;
    q.y = (r[0][2] - r[2][0]) / s;
    q.z = (r[1][0] - r[0][1]) / s;
  } else if (r[0][0] >= r[1][1] && r[0][0] >= r[2][2]) {
    const double s = 2 * std::sqrt(1 + r[0][0] - r[1][1] - r[2][2]);  // 4x
    q.w = (r[2][1] - r[1][2]) / s;
    q.x = s / 4;
    q.y = (r[0][1] + r[1][0]) / s;
    q.z = (r[0][2] + r[2][0]) / s;
  } else if (r[1][1] >= r[2][2]) {
    const double s = 2 * std::sqrt(1 + r[1][1] - r[0][0] - r[2][2]);  // 4y
    q.w = (r[0][2] - r[2][0]) / s;
    q.x = (r[0][1] + r[1][0]) / s;
    q.y = s / 4;
    q.z = (r[1][2] + r[2][1]) / s;
  } else {
    const double s = 2 * std::sqrt(1 + r[2][2] - r[0][0] - r[1][1]);  // 4z
    q.w = (r[1][0] - r[0][1]) / s;
    q.x = (r[0][2] + r[2][0]) / s;
    q.y = (r[1][2] + r[2][1]) / s;
    q.z = s / 4;
  }
  if (q.w < 0) q = {-q.x, -q.y, -q.z, -q.w};
  const double n = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return {q.x / n, q.y / n, q.z / n, q.w / n};
}

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {
      a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
      a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

Quaternion axis_angle(double ax, double ay, double az, double angle_rad) {
  const double n = std::sqrt(ax * ax + ay * ay + az * az);
  const double s = std::sin(angle_rad / 2) / n;
  return {ax * s, ay * s, az * s, std::cos(angle_rad / 2)};
}

std::array<double, 3> euler_yxz_deg(const RotMat& r) {
  // R = Rz(γ)·Rx(β)·Ry(α). Its bottom row does not depend on γ:
  //   R[2] = (−cosβ·sinα, sinβ, cosβ·cosα)
  // so β = asin(R21) and α = atan2(−R20, R22) (cosβ ≥ 0 on [−90°, 90°]); γ follows from the
  // middle column: R01 = −sinγ·cosβ, R11 = cosγ·cosβ.
  constexpr double kDeg = 180.0 / 3.14159265358979323846;
  const double cb = std::hypot(r[2][0], r[2][2]);
  const double beta = std::atan2(r[2][1], cb);
  double alpha, gamma;
  if (cb > 1e-7) {
    alpha = std::atan2(-r[2][0], r[2][2]);
    gamma = std::atan2(-r[0][1], r[1][1]);
  } else {
    // Gimbal lock: only α ± γ is defined. With γ = 0, R = Rx(±90°)·Ry(α), whose first row is
    // (cosα, 0, sinα).
    gamma = 0;
    alpha = std::atan2(r[0][2], r[0][0]);
  }
  return {alpha * kDeg, beta * kDeg, gamma * kDeg};
}

double yaw_yxz_deg(const Quaternion& q) { return euler_yxz_deg(quaternion_to_matrix(q))[0]; }

}  // namespace neraf::geometry
