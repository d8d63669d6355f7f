#include "neraf/dsp/convolve.h"

#include <algorithm>

#include "neraf/dsp/fft_plans.h"

namespace neraf::dsp {
namespace {

using detail::AlignedFloats;
using detail::FftKind;

// Below this many taps a direct sum is both faster and exact to float rounding.
constexpr size_t kDirectMaxTaps = 32;

size_t next_pow2(size_t n) {
  size_t p = 1;
  while (p < n) p <<= 1;
  return p;
}

std::vector<float> direct_convolve(const std::vector<float>& x, const std::vector<float>& h) {
  std::vector<float> y(x.size() + h.size() - 1);
  for (size_t i = 0; i < y.size(); ++i) {
    const size_t k_lo = i >= x.size() ? i - x.size() + 1 : 0;
    const size_t k_hi = std::min(i, h.size() - 1);
    double acc = 0.0;
    for (size_t k = k_lo; k <= k_hi; ++k) acc += double(h[k]) * x[i - k];
    y[i] = static_cast<float>(acc);
  }
  return y;
}

// buf (2·(n/2+1) floats, spectrum of the input) *= spec / n, in place.
void multiply_spectra(float* buf, const float* spec, size_t n) {
  const float scale = 1.0f / static_cast<float>(n);
  for (size_t k = 0; k < n / 2 + 1; ++k) {
    const float re = buf[2 * k] * spec[2 * k] - buf[2 * k + 1] * spec[2 * k + 1];
    const float im = buf[2 * k] * spec[2 * k + 1] + buf[2 * k + 1] * spec[2 * k];
    buf[2 * k] = re * scale;
    buf[2 * k + 1] = im * scale;
  }
}

}  // namespace

std::vector<float> fft_convolve(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.empty() || b.empty()) return {};
  const std::vector<float>& x = a.size() >= b.size() ? a : b;  // the long signal
  const std::vector<float>& h = a.size() >= b.size() ? b : a;  // the kernel
  if (h.size() <= kDirectMaxTaps) return direct_convolve(x, h);

  const size_t m = h.size();
  const size_t out_len = x.size() + m - 1;
  // Power-of-two transforms: cheap to plan (odd sizes can take FFTW_ESTIMATE 100+ ms to plan) and
  // fast. When the signal is much longer than the kernel, overlap-save with blocks of 4× the
  // kernel keeps the transforms in cache (~2.5× faster than one huge transform for 10 s ⊛ 1 s).
  const size_t n = std::min(next_pow2(out_len), next_pow2(4 * m));
  const size_t nc2 = 2 * (n / 2 + 1);
  const fftwf_plan r2c = detail::fft_plan(FftKind::r2c_inplace, static_cast<int>(n));
  const fftwf_plan c2r = detail::fft_plan(FftKind::c2r_inplace, static_cast<int>(n));

  AlignedFloats spec = detail::alloc_floats(nc2);  // H, the kernel's spectrum
  std::copy(h.begin(), h.end(), spec.get());
  fftwf_execute_dft_r2c(r2c, spec.get(), reinterpret_cast<fftwf_complex*>(spec.get()));

  std::vector<float> y(out_len);
  // Overlap-save: block k yields outputs [k·L, k·L + L) from inputs [k·L − (m−1), k·L + L), with
  // L = n − m + 1 (the circular wrap only touches the first m − 1 samples, which are dropped).
  // Blocks write disjoint outputs, so they run in parallel with identical results (handed out one
  // at a time: a thread that gets descheduled on a busy machine delays at most one block).
  const size_t L = n - m + 1;
  const int64_t n_blocks = static_cast<int64_t>((out_len + L - 1) / L);
  const int64_t nx = static_cast<int64_t>(x.size());
#pragma omp parallel if (n_blocks > 1)
  {
    AlignedFloats buf = detail::alloc_floats(nc2);
#pragma omp for schedule(dynamic, 1)
    for (int64_t k = 0; k < n_blocks; ++k) {
      const int64_t start = k * int64_t(L) - int64_t(m - 1);
      float* s = buf.get();
      for (int64_t j = 0; j < int64_t(n); ++j) {
        const int64_t i = start + j;
        s[j] = (i >= 0 && i < nx) ? x[i] : 0.0f;
      }
      fftwf_execute_dft_r2c(r2c, s, reinterpret_cast<fftwf_complex*>(s));
      multiply_spectra(s, spec.get(), n);
      fftwf_execute_dft_c2r(c2r, reinterpret_cast<fftwf_complex*>(s), s);
      const size_t first = size_t(k) * L;
      const size_t count = std::min(L, out_len - first);
      std::copy(s + (m - 1), s + (m - 1) + count, y.begin() + first);
    }
  }
  return y;
}

}  // namespace neraf::dsp
