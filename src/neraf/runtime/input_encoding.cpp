#include "neraf/runtime/input_encoding.h"

#include <algorithm>
#include <cmath>

namespace neraf::rt {

std::array<float, kNumFrequencies> encoding_frequencies(double max_exp) {
  // torch's CPU linspace: step = (end − start)/(n − 1); the first half start + step·i, the second
  // end − step·(n − 1 − i), all in float32 (10 values: the scalar path).
  const int n = kNumFrequencies;
  const float start = 0.0f, end = static_cast<float>(max_exp);
  const float step = (end - start) / float(n - 1);
  std::array<float, kNumFrequencies> f{};
  for (int i = 0; i < n; ++i) {
    const float e = i < n / 2 ? start + step * float(i) : end - step * float(n - 1 - i);
    f[i] = std::pow(2.0f, e);
  }
  return f;
}

std::array<double, 3> normalize_position(const double p[3], const std::array<double, 3>& box_min,
                                         const std::array<double, 3>& box_max) {
  std::array<double, 3> q{};
  for (int k = 0; k < 3; ++k) {
    q[k] = (p[k] - box_min[k]) / (box_max[k] - box_min[k]);
    if (!(q[k] > 0.0 && q[k] < 1.0)) return {0.0, 0.0, 0.0};
  }
  return q;
}

std::array<double, 3> rot_from_yaw(double yaw_deg) {
  const double th = yaw_deg * M_PI / 180.0;
  return {(std::cos(th) + 1) / 2, 0.5, (std::sin(th) + 1) / 2};
}

void encode_time(int t, int n_frames, const std::array<float, kNumFrequencies>& freqs, float* out) {
  const float x = static_cast<float>(t) / static_cast<float>(n_frames - 1);
  const float scaled = x * static_cast<float>(2.0 * M_PI);
  const float half_pi = static_cast<float>(M_PI / 2.0);
  for (int k = 0; k < kNumFrequencies; ++k) {
    const float s = scaled * freqs[k];
    out[k] = std::sin(s);
    out[kNumFrequencies + k] = std::sin(s + half_pi);
  }
  out[2 * kNumFrequencies] = x;
}

void encode_position(const std::array<double, 3>& p,
                     const std::array<float, kNumFrequencies>& freqs, double* out) {
  const int n = kNumFrequencies;
  for (int d = 0; d < 3; ++d) {
    const double scaled = p[d] * (2.0 * M_PI);
    for (int k = 0; k < n; ++k) {
      const double s = scaled * double(freqs[k]);
      out[d * n + k] = std::sin(s);                       // all sines, dim-major
      out[3 * n + d * n + k] = std::sin(s + M_PI / 2.0);  // then all "cosines"
    }
  }
  for (int d = 0; d < 3; ++d) out[6 * n + d] = p[d];  // the raw input last
}

void encode_rot(const std::array<double, 3>& rot, double* o) {
  // nerf::sh_values with tcnn's signs (src/neraf/nerf/sh_encoding.cpp).
  const double x = rot[0] * 2 - 1, y = rot[1] * 2 - 1, z = rot[2] * 2 - 1;
  const double xy = x * y, xz = x * z, yz = y * z, x2 = x * x, y2 = y * y, z2 = z * z;
  o[0] = 0.28209479177387814;
  o[1] = -0.48860251190291987 * y;
  o[2] = 0.48860251190291987 * z;
  o[3] = -0.48860251190291987 * x;
  o[4] = 1.0925484305920792 * xy;
  o[5] = -1.0925484305920792 * yz;
  o[6] = 0.94617469575755997 * z2 - 0.31539156525251999;
  o[7] = -1.0925484305920792 * xz;
  o[8] = 0.54627421529603959 * x2 - 0.54627421529603959 * y2;
  o[9] = 0.59004358992664352 * y * (-3.0 * x2 + y2);
  o[10] = 2.8906114426405538 * xy * z;
  o[11] = 0.45704579946446572 * y * (1.0 - 5.0 * z2);
  o[12] = 0.3731763325901154 * z * (5.0 * z2 - 3.0);
  o[13] = 0.45704579946446572 * x * (1.0 - 5.0 * z2);
  o[14] = 1.4453057213202769 * z * (x2 - y2);
  o[15] = 0.59004358992664352 * x * (-x2 + 3.0 * y2);
}

void encode_relative_geometry(const std::array<double, 3>& mic_m,
                              const std::array<double, 3>& src_m, const std::array<double, 3>& rot,
                              const std::array<double, 3>& extent_m, double* out) {
  double d[3];
  for (int k = 0; k < 3; ++k) d[k] = src_m[k] - mic_m[k];  // metres
  const double dist = std::max(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), 0.05);
  const double horizontal = std::sqrt(d[0] * d[0] + d[2] * d[2]);
  const double heading = std::atan2(2 * rot[2] - 1, 2 * rot[0] - 1);
  const double azimuth = std::atan2(d[2], d[0]);
  int i = 0;
  for (int k = 1; k <= 3; ++k)
    for (const double angle : {azimuth - heading, azimuth + heading}) {
      out[i++] = std::cos(k * angle);
      out[i++] = std::sin(k * angle);
    }
  out[i++] = d[1] / dist;
  out[i++] = horizontal / dist;
  const double diagonal =
      std::sqrt(extent_m[0] * extent_m[0] + extent_m[1] * extent_m[1] + extent_m[2] * extent_m[2]);
  const double relative_dist = dist / diagonal;
  out[i++] = relative_dist;
  out[i++] = std::log(dist);
  for (int k = 0; k < 3; ++k) {
    out[i++] = std::sin(2 * M_PI * std::ldexp(1.0, k) * relative_dist);
    out[i++] = std::cos(2 * M_PI * std::ldexp(1.0, k) * relative_dist);
  }
}

}  // namespace neraf::rt
