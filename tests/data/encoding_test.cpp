// Quaternion/Euler conventions (RAF source yaw), heading encoding and NeRAF's position
// normalisation, against hand-computed values.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

#include "neraf/data/rir_set.h"
#include "neraf/geometry/quaternion.h"

namespace neraf {
namespace {

using geometry::Quaternion;
using geometry::RotMat;

constexpr double kDeg = M_PI / 180.0;

Quaternion yaw_quat(double deg) {  // rotation about +y, [x, y, z, w]
  return {0.0, std::sin(deg * kDeg / 2), 0.0, std::cos(deg * kDeg / 2)};
}

TEST(Quaternion, PureYawAboutYGivesTheAngle) {
  // scipy: R.from_quat([0, sin(θ/2), 0, cos(θ/2)]).as_euler('yxz', degrees=True) = [θ, 0, 0].
  for (const double deg : {30.0, 90.0, -120.0}) {
    const auto e = geometry::euler_yxz_deg(geometry::quaternion_to_matrix(yaw_quat(deg)));
    EXPECT_NEAR(e[0], deg, 1e-9) << deg;
    EXPECT_NEAR(e[1], 0.0, 1e-9);
    EXPECT_NEAR(e[2], 0.0, 1e-9);
    EXPECT_NEAR(geometry::yaw_yxz_deg(yaw_quat(deg)), deg, 1e-9);
  }
}

TEST(Quaternion, MatrixOfYaw30IsHandComputed) {
  // Ry(30°) = [[c, 0, s], [0, 1, 0], [−s, 0, c]].
  const RotMat r = geometry::quaternion_to_matrix(yaw_quat(30));
  const double c = std::sqrt(3.0) / 2, s = 0.5;
  const double want[3][3] = {{c, 0, s}, {0, 1, 0}, {-s, 0, c}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(r[i][j], want[i][j], 1e-12);
}

TEST(Quaternion, UnnormalisedInputIsNormalisedLikeScipy) {
  Quaternion q = yaw_quat(-120);
  q = {q.x * 3, q.y * 3, q.z * 3, q.w * 3};
  EXPECT_NEAR(geometry::yaw_yxz_deg(q), -120.0, 1e-9);
}

TEST(Quaternion, ExtrinsicYxzOfACompositeRotation) {
  // R = Rz(10°)·Rx(20°)·Ry(30°) (extrinsic y, then x, then z) -> angles (30, 20, 10).
  const Quaternion q =
      geometry::multiply(geometry::axis_angle(0, 0, 1, 10 * kDeg),
                         geometry::multiply(geometry::axis_angle(1, 0, 0, 20 * kDeg),
                                            geometry::axis_angle(0, 1, 0, 30 * kDeg)));
  const auto e = geometry::euler_yxz_deg(geometry::quaternion_to_matrix(q));
  EXPECT_NEAR(e[0], 30, 1e-9);
  EXPECT_NEAR(e[1], 20, 1e-9);
  EXPECT_NEAR(e[2], 10, 1e-9);
  // Negative pitch and a yaw beyond 90°: (−150, −40, 75).
  const Quaternion q2 =
      geometry::multiply(geometry::axis_angle(0, 0, 1, 75 * kDeg),
                         geometry::multiply(geometry::axis_angle(1, 0, 0, -40 * kDeg),
                                            geometry::axis_angle(0, 1, 0, -150 * kDeg)));
  const auto e2 = geometry::euler_yxz_deg(geometry::quaternion_to_matrix(q2));
  EXPECT_NEAR(e2[0], -150, 1e-9);
  EXPECT_NEAR(e2[1], -40, 1e-9);
  EXPECT_NEAR(e2[2], 75, 1e-9);
}

TEST(Quaternion, GimbalLockSetsTheThirdAngleToZero) {
  // Rx(90°)·Ry(25°): β = 90°, scipy reports (25, 90, 0).
  const Quaternion q = geometry::multiply(geometry::axis_angle(1, 0, 0, 90 * kDeg),
                                          geometry::axis_angle(0, 1, 0, 25 * kDeg));
  const auto e = geometry::euler_yxz_deg(geometry::quaternion_to_matrix(q));
  EXPECT_NEAR(e[0], 25, 1e-6);
  EXPECT_NEAR(e[1], 90, 1e-6);
  EXPECT_EQ(e[2], 0.0);
}

TEST(Quaternion, MatrixQuaternionRoundTrip) {
  const Quaternion q =
      geometry::multiply(geometry::axis_angle(1, 2, 3, 2.0), geometry::axis_angle(0, 0, 1, 1.0));
  const Quaternion back = geometry::matrix_to_quaternion(geometry::quaternion_to_matrix(q));
  const double sign = (back.w * q.w >= 0) ? 1.0 : -1.0;
  EXPECT_NEAR(back.x, sign * q.x, 1e-12);
  EXPECT_NEAR(back.y, sign * q.y, 1e-12);
  EXPECT_NEAR(back.z, sign * q.z, 1e-12);
  EXPECT_NEAR(back.w, sign * q.w, 1e-12);
  // Near-180° rotations take the non-trace branches.
  for (const auto& axis : {std::array<double, 3>{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}) {
    const Quaternion r = geometry::axis_angle(axis[0], axis[1], axis[2], 3.1);
    const RotMat m = geometry::quaternion_to_matrix(r);
    const RotMat m2 = geometry::quaternion_to_matrix(geometry::matrix_to_quaternion(m));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) EXPECT_NEAR(m[i][j], m2[i][j], 1e-12);
  }
}

TEST(Encoding, HeadingRotIsTheReferenceFormula) {
  auto r = data::encode_heading(0);
  EXPECT_DOUBLE_EQ(r[0], 1.0);
  EXPECT_DOUBLE_EQ(r[1], 0.5);
  EXPECT_DOUBLE_EQ(r[2], 0.5);
  r = data::encode_heading(90);
  EXPECT_NEAR(r[0], 0.5, 1e-15);
  EXPECT_NEAR(r[2], 1.0, 1e-15);
  r = data::encode_heading(270);
  EXPECT_NEAR(r[0], 0.5, 1e-15);
  EXPECT_NEAR(r[2], 0.0, 1e-15);
  r = data::encode_heading(-120);
  EXPECT_NEAR(r[0], (std::cos(-120 * kDeg) + 1) / 2, 1e-15);
  EXPECT_NEAR(r[2], (std::sin(-120 * kDeg) + 1) / 2, 1e-15);
}

TEST(Encoding, PositionNormalisationZeroesTheWholeVectorOutsideTheOpenBox) {
  const data::Aabb box{{-1, 0, 2}, {3, 2, 6}};
  auto p = data::normalize_position(geometry::Vec3{1, 0.5, 5}, box);
  EXPECT_DOUBLE_EQ(p.x, 0.5);
  EXPECT_DOUBLE_EQ(p.y, 0.25);
  EXPECT_DOUBLE_EQ(p.z, 0.75);
  // One component outside, or exactly on a face (the interval is open): all three become 0.
  for (const geometry::Vec3 q : {geometry::Vec3{1, 0.5, 7}, geometry::Vec3{-1, 0.5, 5},
                                 geometry::Vec3{1, 2, 5}, geometry::Vec3{1, -0.1, 5}}) {
    const auto z = data::normalize_position(q, box);
    EXPECT_EQ(z.x, 0.0);
    EXPECT_EQ(z.y, 0.0);
    EXPECT_EQ(z.z, 0.0);
  }
  const torch::Tensor pts =
      torch::tensor({1.0, 0.5, 5.0, 1.0, 0.5, 7.0, 2.0, 1.0, 3.0}, torch::kFloat64).view({3, 3});
  const torch::Tensor n = data::normalize_position(pts, box);
  const torch::Tensor want =
      torch::tensor({0.5, 0.25, 0.75, 0.0, 0.0, 0.0, 0.75, 0.5, 0.25}, torch::kFloat64)
          .view({3, 3});
  EXPECT_TRUE(torch::allclose(n, want, 0, 1e-15)) << n;
}

}  // namespace
}  // namespace neraf
