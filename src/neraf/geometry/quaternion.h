#pragma once
// Unit quaternions in scipy's scalar-last order [x, y, z, w], rotation matrices, and the Euler
// yaw that the published NeRAF code reads from RAF source poses:
//   θ = R.from_quat([qx, qy, qz, qw]).as_euler('yxz', degrees=True)[0]
// (lower-case 'yxz' = extrinsic rotations about the fixed y, then x, then z axis, so
// R = Rz(γ)·Rx(β)·Ry(α) and the first angle α is the rotation about +y, the "up" axis).
#include <array>

#include "neraf/geometry/pose.h"  // struct Quaternion {x, y, z, w}: scalar last (scipy / RAF order)

namespace neraf::geometry {

using RotMat = std::array<std::array<double, 3>, 3>;  // row-major, R[row][col]

// Rotation matrix of q. Like scipy's from_quat, q is normalised first; a zero (or non-finite)
// quaternion has no rotation and yields a matrix of NaNs.
RotMat quaternion_to_matrix(const Quaternion& q);

// A unit quaternion with w >= 0 for a proper rotation matrix (Shepperd's method).
Quaternion matrix_to_quaternion(const RotMat& r);

// Hamilton product a·b (apply b first, then a).
Quaternion multiply(const Quaternion& a, const Quaternion& b);

// Quaternion of a rotation by `angle_rad` about the axis (ax, ay, az) (normalised here).
Quaternion axis_angle(double ax, double ay, double az, double angle_rad);

// scipy's as_euler('yxz') in degrees: {α about y, β about x, γ about z} with R = Rz(γ)Rx(β)Ry(α),
// α, γ ∈ (−180, 180], β ∈ [−90, 90]. At gimbal lock (|β| = 90°) γ is set to 0, as scipy does
// (scipy also warns).
std::array<double, 3> euler_yxz_deg(const RotMat& r);

// The yaw NeRAF uses for RAF sources: euler_yxz_deg(R(q))[0] (degrees, not rounded).
double yaw_yxz_deg(const Quaternion& q);

}  // namespace neraf::geometry
