#pragma once
// Branch-free float exp, log and tanh that the compiler vectorises when called in a plain loop
// (libm's are scalar calls: ~40k of each per RIR would cost more than the network; GCC needs
// -fno-trapping-math to if-convert the clamps, see cmake/runtime.cmake). Accuracy,
// checked against double libm in tests/runtime/vector_math_test.cpp:
//   exp_approx   relative error < 1e-7 on [−87, 88] (Cephes expf)
//   log_approx   absolute error < 6e-7 for normal x > 0, up to 1e5 (Cephes logf)
//   tanh_approx  absolute error < 1.5e-7 (a rational fit below 0.625, 1 − 2/(e^{2|x|} + 1) above)
// exp_approx and tanh_approx give NaN for NaN; other inputs outside those domains (NaN or x ≤ 0
// for log) give unspecified values, never traps.
#include <cmath>
#include <cstdint>
#include <cstring>

namespace neraf::rt {

inline float bits_to_float(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
inline uint32_t float_to_bits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

inline float exp_approx(float x) {
  x = x < -87.0f ? -87.0f : (x > 88.0f ? 88.0f : x);
  // n = floor(x·log2(e) + 1/2), so x = n·ln2 + r with |r| ≤ ln2/2. (Truncation of a value made
  // positive: std::floor keeps the loop from vectorising.) The clamps let a NaN through, and
  // converting a NaN to int is undefined behaviour: n is taken from xn, which is x except that a
  // NaN becomes −87 (and still comes out NaN through r). This form GCC still vectorises.
  const float xn = x > -87.0f ? x : -87.0f;
  const float n = float(int32_t(xn * 1.44269504088896341f + 128.5f)) - 128.0f;
  const float r = (x - n * 0.693359375f) - n * -2.12194440e-4f;  // ln2 in two parts: exact n·C1
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  return p * bits_to_float(uint32_t(int32_t(n) + 127) << 23);  // · 2^n
}

inline float log_approx(float x) {
  const uint32_t u = float_to_bits(x);
  int32_t e = int32_t(u >> 23) - 126;                         // x = m·2^e, m in [0.5, 1)
  float m = bits_to_float((u & 0x007FFFFFu) | 0x3F000000u);
  const bool below = m < 0.707106781186547524f;                // keep m − 1 in [−0.29, 0.41]
  e = below ? e - 1 : e;
  m = below ? m + m - 1.0f : m - 1.0f;
  const float z = m * m;
  float y = 7.0376836292e-2f;
  y = y * m - 1.1514610310e-1f;
  y = y * m + 1.1676998740e-1f;
  y = y * m - 1.2420140846e-1f;
  y = y * m + 1.4249322787e-1f;
  y = y * m - 1.6668057665e-1f;
  y = y * m + 2.0000714765e-1f;
  y = y * m - 2.4999993993e-1f;
  y = y * m + 3.3333331174e-1f;
  y = y * m * z;
  const float fe = float(e);
  y += fe * -2.12194440e-4f;
  y += -0.5f * z;
  return m + y + fe * 0.693359375f;
}

inline float tanh_approx(float a) {
  const float ax = std::fabs(a);
  // |a| < 0.625: Eigen's [13/6] rational fit of tanh (odd numerator, even denominator), where
  // 1 − 2/(e + 1) would cancel.
  const float x2 = a * a;
  float p = x2 * -2.76076847742355e-16f + 2.00018790482477e-13f;
  p = x2 * p + -8.60467152213735e-11f;
  p = x2 * p + 5.12229709037114e-08f;
  p = x2 * p + 1.48572235717979e-05f;
  p = x2 * p + 6.37261928875436e-04f;
  p = x2 * p + 4.89352455891786e-03f;
  p = a * p;
  float q = x2 * 1.19825839466702e-06f + 1.18534705686654e-04f;
  q = x2 * q + 2.26843463243900e-03f;
  q = x2 * q + 4.89352518554385e-03f;
  const float small = p / q;
  const float e = exp_approx(2.0f * (ax > 10.0f ? 10.0f : ax));  // tanh(x > 9.1) rounds to 1
  const float big = std::copysign(1.0f - 2.0f / (e + 1.0f), a);
  // A bitwise select: GCC does not if-convert `ax < 0.625f ? small : big` here.
  const uint32_t use_small = 0u - uint32_t(ax < 0.625f);
  return bits_to_float((float_to_bits(small) & use_small) | (float_to_bits(big) & ~use_small));
}

}  // namespace neraf::rt
