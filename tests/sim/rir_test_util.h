#pragma once
// Shared helpers of the RIR simulator tests: a small scene builder and signal measurements written
// independently of the simulator (own band-pass filter, own Schroeder fit).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "neraf/sim/scene.h"

namespace neraf::sim::testing {

// An empty shoebox whose six surfaces share one material with the given absorption.
inline Scene shoebox(Vec3 size, double absorption, double scattering = 0.1, int max_order = 8,
                     double length_s = 1.0) {
  Scene s;
  s.size = size;
  Material m;
  m.absorption.fill(absorption);
  m.scattering = scattering;
  for (const char* name : {"wall", "floor", "ceiling"}) s.materials[name] = m;
  s.acoustics.max_order = max_order;
  s.acoustics.rir_length_s = length_s;
  return s;
}

inline double energy(const std::vector<float>& x, size_t from = 0, size_t to = SIZE_MAX) {
  const float* p = x.data();
  const size_t end = std::min(to, x.size());
  double e = 0;
  for (size_t i = from; i < end; ++i) e += double(p[i]) * p[i];
  return e;
}

inline size_t argmax_abs(const std::vector<float>& x) {
  size_t best = 0;
  for (size_t i = 1; i < x.size(); ++i)
    if (std::abs(x[i]) > std::abs(x[best])) best = i;
  return best;
}

// First index whose |value| reaches `fraction` of the peak |value|.
inline size_t onset(const std::vector<float>& x, double fraction = 0.1) {
  const double peak = std::abs(x[argmax_abs(x)]);
  for (size_t i = 0; i < x.size(); ++i)
    if (std::abs(x[i]) >= fraction * peak) return i;
  return x.size();
}

// Octave band-pass: two cascaded RBJ band-pass biquads (0 dB peak), Q = sqrt(2).
inline std::vector<float> octave_bandpass(const std::vector<float>& x, double fs, double fc) {
  const double w0 = 2 * M_PI * fc / fs, alpha = std::sin(w0) / (2 * std::sqrt(2.0)),
               c = std::cos(w0);
  const double a0 = 1 + alpha, b0 = alpha / a0, b2 = -alpha / a0, a1 = -2 * c / a0,
               a2 = (1 - alpha) / a0;
  std::vector<double> y(x.begin(), x.end());
  for (int pass = 0; pass < 2; ++pass) {
    double x1 = 0, x2 = 0, y1 = 0, y2 = 0;
    for (double& v : y) {
      const double out = b0 * v + b2 * x2 - a1 * y1 - a2 * y2;
      x2 = x1;
      x1 = v;
      y2 = y1;
      y1 = out;
      v = out;
    }
  }
  return std::vector<float>(y.begin(), y.end());
}

// T60 from the Schroeder backward integral by a least-squares line through −5..−35 dB.
inline double schroeder_t60(const std::vector<float>& h, double fs) {
  std::vector<double> e(h.size());
  double acc = 0;
  for (size_t i = h.size(); i-- > 0;) {
    acc += double(h[i]) * h[i];
    e[i] = acc;
  }
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (size_t i = 0; i < e.size(); ++i) {
    const double db = 10 * std::log10(e[i] / e[0]);
    if (db > -5) continue;
    if (db < -35) break;
    const double t = i / fs;
    sx += t, sy += db, sxx += t * t, sxy += t * db;
    ++n;
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);  // dB per second
  return -60 / slope;
}

}  // namespace neraf::sim::testing
