#include "neraf/nerf/hash_grid_kernel.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "neraf/util/error.h"

namespace neraf::nerf {

HashGridLayout HashGridLayout::make(const HashGridConfig& c) {
  const std::string where = "hash grid config: ";
  require(c.num_levels >= 1 && c.num_levels <= 32,
          where + "num_levels must be in [1, 32], got " + std::to_string(c.num_levels));
  require(c.features_per_level == 1 || c.features_per_level == 2 || c.features_per_level == 4 ||
              c.features_per_level == 8,
          where + "features_per_level must be 1, 2, 4 or 8, got " +
              std::to_string(c.features_per_level));
  require(c.log2_hashmap_size >= 3 && c.log2_hashmap_size <= 30,
          where + "log2_hashmap_size must be in [3, 30], got " +
              std::to_string(c.log2_hashmap_size));
  require(c.base_resolution >= 1 && c.base_resolution <= 1 << 16,
          where + "base_resolution must be in [1, 65536], got " +
              std::to_string(c.base_resolution));
  require(c.max_resolution >= c.base_resolution && c.max_resolution <= 1 << 20,
          where + "max_resolution must be in [base_resolution, 2^20], got " +
              std::to_string(c.max_resolution));

  HashGridLayout layout;
  layout.config = c;
  // nerfstudio computes the growth factor in double and tcnn stores it as a float.
  layout.per_level_scale =
      c.num_levels > 1 ? static_cast<float>(std::exp(
                             (std::log(static_cast<double>(c.max_resolution)) -
                              std::log(static_cast<double>(c.base_resolution))) /
                             (c.num_levels - 1)))
                       : 1.0f;
  const float log2_scale = std::log2(layout.per_level_scale);
  const uint64_t hashmap_size = uint64_t{1} << c.log2_hashmap_size;
  int64_t offset = 0;
  for (int l = 0; l < c.num_levels; ++l) {
    const float scale =
        std::exp2(static_cast<float>(l) * log2_scale) * static_cast<float>(c.base_resolution) -
        1.0f;
    const uint64_t res = static_cast<uint64_t>(std::ceil(scale)) + 1;
    const uint64_t dense_size = res * res * res;
    const uint64_t padded = (dense_size + 7) / 8 * 8;  // tcnn aligns each level to 8 entries
    const uint64_t size = std::min(padded, hashmap_size);
    layout.offsets.push_back(offset);
    layout.sizes.push_back(static_cast<int64_t>(size));
    layout.scales.push_back(scale);
    layout.resolutions.push_back(static_cast<int64_t>(res));
    layout.dense.push_back(dense_size <= size ? 1 : 0);
    offset += static_cast<int64_t>(size);
  }
  layout.offsets.push_back(offset);
  layout.total_entries = offset;
  return layout;
}

namespace {

constexpr uint32_t kPrimeY = 2654435761u;
constexpr uint32_t kPrimeZ = 805459861u;

// One level, prepared for the inner loops.
struct Level {
  uint32_t size;  // table rows
  uint32_t mask;  // size − 1 (hashed levels: size is a power of two)
  uint32_t res, res2;
  float scale;
};

Level level_of(const HashGridLayout& layout, int l) {
  Level lv;
  lv.size = static_cast<uint32_t>(layout.sizes[l]);
  lv.mask = lv.size - 1;
  lv.res = static_cast<uint32_t>(layout.resolutions[l]);
  lv.res2 = lv.res * lv.res;
  lv.scale = layout.scales[l];
  return lv;
}

// The 8 corner rows and the fractional position of one point at one level. Corner c has the
// offset (c & 1, (c >> 1) & 1, c >> 2), tcnn's order. All index arithmetic is uint32 as in tcnn.
template <typename T, bool kDense>
inline void locate(const T* p, const Level& lv, uint32_t idx[8], T frac[3]) {
  uint32_t g[3];
  const T scale = static_cast<T>(lv.scale);
  for (int d = 0; d < 3; ++d) {
    const T pos = std::fma(p[d], scale, T(0.5));
    const T fl = std::floor(pos);
    g[d] = static_cast<uint32_t>(static_cast<int32_t>(fl));
    frac[d] = pos - fl;
  }
  if (kDense) {
    const uint32_t base = g[0] + g[1] * lv.res + g[2] * lv.res2;
    const uint32_t off[8] = {0u,      1u,          lv.res,          lv.res + 1u,
                             lv.res2, lv.res2 + 1, lv.res2 + lv.res, lv.res2 + lv.res + 1u};
    for (int c = 0; c < 8; ++c) {
      const uint32_t v = base + off[c];
      // The +0.5 offset can push the top corner one past the grid: tcnn wraps it with a modulo.
      idx[c] = v < lv.size ? v : v - lv.size + 1;
    }
  } else {
    const uint32_t hx[2] = {g[0], g[0] + 1u};
    const uint32_t hy0 = g[1] * kPrimeY, hz0 = g[2] * kPrimeZ;
    const uint32_t hy[2] = {hy0, hy0 + kPrimeY};
    const uint32_t hz[2] = {hz0, hz0 + kPrimeZ};
    for (int c = 0; c < 8; ++c) idx[c] = (hx[c & 1] ^ hy[(c >> 1) & 1] ^ hz[c >> 2]) & lv.mask;
  }
}

// Trilinear weights in tcnn's product order ((wx · wy) · wz).
template <typename T>
inline void weights(const T frac[3], T w[8]) {
  const T wx[2] = {T(1) - frac[0], frac[0]};
  const T wy[2] = {T(1) - frac[1], frac[1]};
  const T wz[2] = {T(1) - frac[2], frac[2]};
  for (int c = 0; c < 8; ++c) w[c] = wx[c & 1] * wy[(c >> 1) & 1] * wz[c >> 2];
}

// Below this many points per thread the OpenMP fork costs more than it saves.
constexpr int64_t kMinPointsPerThread = 2048;

int threads_for(int64_t n, int num_threads) {
  const int64_t useful = std::max<int64_t>(1, n / kMinPointsPerThread);
  return static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(num_threads, useful)));
}

// out_level: [n, F] contiguous rows of this level (a scratch buffer, level-major).
template <typename T, int F, bool kDense>
void forward_level(const T* x, int64_t begin, int64_t end, const T* table, const Level& lv,
                   T* out_level) {
  for (int64_t i = begin; i < end; ++i) {
    uint32_t idx[8];
    T frac[3], w[8];
    locate<T, kDense>(x + 3 * i, lv, idx, frac);
    weights(frac, w);
    T acc[F];
    for (int f = 0; f < F; ++f) acc[f] = T(0);
    for (int c = 0; c < 8; ++c) {
      const T* v = table + static_cast<int64_t>(idx[c]) * F;
      for (int f = 0; f < F; ++f) acc[f] = std::fma(w[c], v[f], acc[f]);
    }
    T* o = out_level + i * F;
    for (int f = 0; f < F; ++f) o[f] = acc[f];
  }
}

// grad_level: [n, F] upstream gradient of this level (level-major scratch).
// grad_x_level: [n, 3] this level's contribution to dL/dx, or null.
template <typename T, int F, bool kDense>
void backward_level(const T* x, int64_t n, const T* table, const T* grad_level, const Level& lv,
                    T* grad_table, T* grad_x_level) {
  const T scale = static_cast<T>(lv.scale);
  for (int64_t i = 0; i < n; ++i) {
    uint32_t idx[8];
    T frac[3], w[8];
    locate<T, kDense>(x + 3 * i, lv, idx, frac);
    weights(frac, w);
    const T* g = grad_level + i * F;
    for (int c = 0; c < 8; ++c) {
      T* dst = grad_table + static_cast<int64_t>(idx[c]) * F;
      for (int f = 0; f < F; ++f) dst[f] += w[c] * g[f];
    }
    if (grad_x_level != nullptr) {
      // d out_f / d frac_d = Σ_c (±1) · (product of the other two 1-D weights) · v_cf.
      T gv[8];
      for (int c = 0; c < 8; ++c) {
        const T* v = table + static_cast<int64_t>(idx[c]) * F;
        T s = T(0);
        for (int f = 0; f < F; ++f) s += g[f] * v[f];
        gv[c] = s;
      }
      const T wx[2] = {T(1) - frac[0], frac[0]};
      const T wy[2] = {T(1) - frac[1], frac[1]};
      const T wz[2] = {T(1) - frac[2], frac[2]};
      T d[3] = {T(0), T(0), T(0)};
      for (int c = 0; c < 8; ++c) {
        const int bx = c & 1, by = (c >> 1) & 1, bz = c >> 2;
        const T sx = bx ? T(1) : T(-1), sy = by ? T(1) : T(-1), sz = bz ? T(1) : T(-1);
        d[0] += sx * wy[by] * wz[bz] * gv[c];
        d[1] += sy * wx[bx] * wz[bz] * gv[c];
        d[2] += sz * wx[bx] * wy[by] * gv[c];
      }
      T* gx = grad_x_level + 3 * i;
      for (int k = 0; k < 3; ++k) gx[k] = scale * d[k];
    }
  }
}

// Row block of F values, copied as one unit by the transposes.
template <typename T, int F>
struct Row {
  T v[F];
};

// [L, n, F] (level-major) → [n, L·F] (point-major), blocked so both sides stream.
template <typename T, int F>
void level_major_to_point_major(const T* src, int64_t n, int L, T* dst, int nt) {
  using R = Row<T, F>;
  const R* s = reinterpret_cast<const R*>(src);
  R* d = reinterpret_cast<R*>(dst);
  constexpr int64_t kBlock = 256;
  const int64_t n_blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t b = 0; b < n_blocks; ++b) {
    const int64_t i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
    for (int l = 0; l < L; ++l) {
      const R* sl = s + l * n;
      for (int64_t i = i0; i < i1; ++i) d[i * L + l] = sl[i];
    }
  }
}

template <typename T, int F>
void point_major_to_level_major(const T* src, int64_t n, int L, T* dst, int nt) {
  using R = Row<T, F>;
  const R* s = reinterpret_cast<const R*>(src);
  R* d = reinterpret_cast<R*>(dst);
  constexpr int64_t kBlock = 256;
  const int64_t n_blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(static) num_threads(nt)
  for (int64_t b = 0; b < n_blocks; ++b) {
    const int64_t i0 = b * kBlock, i1 = std::min(n, i0 + kBlock);
    for (int l = 0; l < L; ++l) {
      R* dl = d + l * n;
      for (int64_t i = i0; i < i1; ++i) dl[i] = s[i * L + l];
    }
  }
}

template <typename T, int F>
void forward_impl(const T* x, int64_t n, const T* table, const HashGridLayout& layout, T* out,
                  int num_threads) {
  const int L = layout.num_levels();
  const int nt = threads_for(n, num_threads);
  // Level-major scratch: each level pass writes one contiguous [n, F] slab instead of touching
  // every row of the point-major output L times.
  std::unique_ptr<T[]> scratch(new T[static_cast<size_t>(n) * L * F]);
#pragma omp parallel num_threads(nt)
  {
    const int tid = omp_get_thread_num(), nth = omp_get_num_threads();
    // A fixed, contiguous share of points per thread (the same split at every level).
    const int64_t begin = n * tid / nth, end = n * (tid + 1) / nth;
    for (int l = 0; l < L; ++l) {
      const Level lv = level_of(layout, l);
      const T* tl = table + layout.offsets[l] * F;
      T* ol = scratch.get() + static_cast<int64_t>(l) * n * F;
      if (layout.dense[l]) {
        forward_level<T, F, true>(x, begin, end, tl, lv, ol);
      } else {
        forward_level<T, F, false>(x, begin, end, tl, lv, ol);
      }
      // Keep the threads on the same level so that only one level's table is hot at a time.
#pragma omp barrier
    }
  }
  level_major_to_point_major<T, F>(scratch.get(), n, L, out, nt);
}

template <typename T, int F>
void backward_impl(const T* x, int64_t n, const T* table, const T* grad_out,
                   const HashGridLayout& layout, T* grad_table, T* grad_x, int num_threads) {
  const int L = layout.num_levels();
  const int nt = threads_for(n, num_threads);
  std::unique_ptr<T[]> grad_lm(new T[static_cast<size_t>(n) * L * F]);
  point_major_to_level_major<T, F>(grad_out, n, L, grad_lm.get(), nt);
  std::unique_ptr<T[]> grad_x_levels;
  if (grad_x != nullptr) grad_x_levels.reset(new T[static_cast<size_t>(n) * L * 3]);

  // Each level is owned by exactly one thread and accumulated in point order, so the result does
  // not depend on which thread takes it: dynamic scheduling (finest, most expensive levels first)
  // balances the load without costing determinism.
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::min(nt, L))
  for (int k = 0; k < L; ++k) {
    const int l = L - 1 - k;
    const Level lv = level_of(layout, l);
    const int64_t off = layout.offsets[l] * F;
    const T* gl = grad_lm.get() + static_cast<int64_t>(l) * n * F;
    T* gxl = grad_x != nullptr ? grad_x_levels.get() + static_cast<int64_t>(l) * n * 3 : nullptr;
    if (layout.dense[l]) {
      backward_level<T, F, true>(x, n, table + off, gl, lv, grad_table + off, gxl);
    } else {
      backward_level<T, F, false>(x, n, table + off, gl, lv, grad_table + off, gxl);
    }
  }

  if (grad_x != nullptr) {
    const T* gxl = grad_x_levels.get();
#pragma omp parallel for schedule(static) num_threads(nt)
    for (int64_t i = 0; i < n * 3; ++i) {
      T s = T(0);
      for (int l = 0; l < L; ++l) s += gxl[static_cast<int64_t>(l) * n * 3 + i];
      grad_x[i] = s;
    }
  }
}

}  // namespace

template <typename T>
void hash_grid_forward_cpu(const T* x, int64_t n, const T* table, const HashGridLayout& layout,
                           T* out, int num_threads) {
  if (n <= 0) return;
  switch (layout.features()) {
    case 1: return forward_impl<T, 1>(x, n, table, layout, out, num_threads);
    case 2: return forward_impl<T, 2>(x, n, table, layout, out, num_threads);
    case 4: return forward_impl<T, 4>(x, n, table, layout, out, num_threads);
    case 8: return forward_impl<T, 8>(x, n, table, layout, out, num_threads);
  }
}

template <typename T>
void hash_grid_backward_cpu(const T* x, int64_t n, const T* table, const T* grad_out,
                            const HashGridLayout& layout, T* grad_table, T* grad_x,
                            int num_threads) {
  if (n <= 0) return;
  switch (layout.features()) {
    case 1: return backward_impl<T, 1>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads);
    case 2: return backward_impl<T, 2>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads);
    case 4: return backward_impl<T, 4>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads);
    case 8: return backward_impl<T, 8>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads);
  }
}

template void hash_grid_forward_cpu<float>(const float*, int64_t, const float*,
                                           const HashGridLayout&, float*, int);
template void hash_grid_forward_cpu<double>(const double*, int64_t, const double*,
                                            const HashGridLayout&, double*, int);
template void hash_grid_backward_cpu<float>(const float*, int64_t, const float*, const float*,
                                            const HashGridLayout&, float*, float*, int);
template void hash_grid_backward_cpu<double>(const double*, int64_t, const double*, const double*,
                                             const HashGridLayout&, double*, double*, int);

}  // namespace neraf::nerf
