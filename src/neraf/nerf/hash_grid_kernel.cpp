#include "neraf/nerf/hash_grid_kernel.h"

// GCC 12 reports false -Wmaybe-uninitialized inside its own AVX-512 intrinsic headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <omp.h>

#if defined(__AVX512F__)
#include <immintrin.h>
#define NERAF_HASH_GRID_AVX512 1
#else
#define NERAF_HASH_GRID_AVX512 0
#endif

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <type_traits>

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
  require(
      c.log2_hashmap_size >= 3 && c.log2_hashmap_size <= 30,
      where + "log2_hashmap_size must be in [3, 30], got " + std::to_string(c.log2_hashmap_size));
  require(
      c.base_resolution >= 1 && c.base_resolution <= 1 << 16,
      where + "base_resolution must be in [1, 65536], got " + std::to_string(c.base_resolution));
  require(c.max_resolution >= c.base_resolution && c.max_resolution <= 1 << 20,
          where + "max_resolution must be in [base_resolution, 2^20], got " +
              std::to_string(c.max_resolution));

  HashGridLayout layout;
  layout.config = c;
  // nerfstudio computes the growth factor in double and tcnn stores it as a float.
  layout.per_level_scale =
      c.num_levels > 1
          ? static_cast<float>(std::exp((std::log(static_cast<double>(c.max_resolution)) -
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
    const uint32_t off[8] = {0u,      1u,          lv.res,           lv.res + 1u,
                             lv.res2, lv.res2 + 1, lv.res2 + lv.res, lv.res2 + lv.res + 1u};
    for (int c = 0; c < 8; ++c) {
      const uint32_t v = base + off[c];
      // The +0.5 offset can push the top corner one past the grid: tcnn wraps it with a modulo.
      idx[c] = v < lv.size ? v : v % lv.size;
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

// ---- scalar path (any T, any F) -----------------------------------------------------------
// Every floating-point step is written out (explicit fma) so that the AVX-512 path below can
// reproduce it lane by lane: both paths give bit-identical results.

template <typename T, int F>
inline void forward_point(const uint32_t idx[8], const T w[8], const T* table, T* o) {
  T acc[F];
  for (int f = 0; f < F; ++f) acc[f] = T(0);
  for (int c = 0; c < 8; ++c) {
    const T* v = table + static_cast<int64_t>(idx[c]) * F;
    for (int f = 0; f < F; ++f) acc[f] = std::fma(w[c], v[f], acc[f]);
  }
  for (int f = 0; f < F; ++f) o[f] = acc[f];
}

template <typename T, int F>
inline void scatter_point(const uint32_t idx[8], const T w[8], const T* g, T* grad_table) {
  for (int c = 0; c < 8; ++c) {
    T* dst = grad_table + static_cast<int64_t>(idx[c]) * F;
    for (int f = 0; f < F; ++f) dst[f] = std::fma(w[c], g[f], dst[f]);
  }
}

// Adds this level's contribution to dL/dx of one point (assigns it when `first`):
// scale · Σ_c (±1) · (product of the other two 1-D weights) · Σ_f g_f · v_cf.
template <typename T, int F>
inline void grad_x_point(const uint32_t idx[8], const T frac[3], const T* g, const T* table,
                         T scale, bool first, T* gx) {
  const T wx[2] = {T(1) - frac[0], frac[0]};
  const T wy[2] = {T(1) - frac[1], frac[1]};
  const T wz[2] = {T(1) - frac[2], frac[2]};
  T d[3] = {T(0), T(0), T(0)};
  for (int c = 0; c < 8; ++c) {
    const T* v = table + static_cast<int64_t>(idx[c]) * F;
    T gv = g[0] * v[0];
    for (int f = 1; f < F; ++f) gv = std::fma(g[f], v[f], gv);
    const int bx = c & 1, by = (c >> 1) & 1, bz = c >> 2;
    const T tyz = wy[by] * wz[bz], txz = wx[bx] * wz[bz], txy = wx[bx] * wy[by];
    d[0] = std::fma(bx ? tyz : -tyz, gv, d[0]);
    d[1] = std::fma(by ? txz : -txz, gv, d[1]);
    d[2] = std::fma(bz ? txy : -txy, gv, d[2]);
  }
  for (int k = 0; k < 3; ++k) gx[k] = first ? scale * d[k] : std::fma(scale, d[k], gx[k]);
}

// out_level: [n, F] rows of this level (level-major scratch); points [begin, end).
template <typename T, int F, bool kDense>
void forward_level_scalar(const T* x, int64_t begin, int64_t end, const T* table, const Level& lv,
                          T* out_level) {
  for (int64_t i = begin; i < end; ++i) {
    uint32_t idx[8];
    T frac[3], w[8];
    locate<T, kDense>(x + 3 * i, lv, idx, frac);
    weights(frac, w);
    forward_point<T, F>(idx, w, table, out_level + i * F);
  }
}

// grad_level: [n, F] upstream gradient of this level (level-major scratch). Points [begin, end)
// in order.
template <typename T, int F, bool kDense>
void scatter_level_scalar(const T* x, int64_t begin, int64_t end, const T* grad_level,
                          const Level& lv, T* grad_table) {
  for (int64_t i = begin; i < end; ++i) {
    uint32_t idx[8];
    T frac[3], w[8];
    locate<T, kDense>(x + 3 * i, lv, idx, frac);
    weights(frac, w);
    scatter_point<T, F>(idx, w, grad_level + i * F, grad_table);
  }
}

// grad_x: [n, 3], this level's contribution added (assigned when `first`).
template <typename T, int F, bool kDense>
void grad_x_level_scalar(const T* x, int64_t begin, int64_t end, const T* table,
                         const T* grad_level, const Level& lv, bool first, T* grad_x) {
  for (int64_t i = begin; i < end; ++i) {
    uint32_t idx[8];
    T frac[3];
    locate<T, kDense>(x + 3 * i, lv, idx, frac);
    grad_x_point<T, F>(idx, frac, grad_level + i * F, table, static_cast<T>(lv.scale), first,
                       grad_x + 3 * i);
  }
}

#if NERAF_HASH_GRID_AVX512
// ---- AVX-512 path (float, F = 2): 16 points per step -----------------------------------------

// Lane indices that deinterleave 16 xyz triples: component k of point j is element 3j + k.
struct XyzPermutes {
  alignas(64) int32_t first[3][16];   // picks from the first 32 floats
  alignas(64) int32_t second[3][16];  // keeps lanes < 32 / picks the rest from the last 16
  constexpr XyzPermutes() : first{}, second{} {
    for (int k = 0; k < 3; ++k) {
      for (int j = 0; j < 16; ++j) {
        const int e = 3 * j + k;
        first[k][j] = e < 32 ? e : 0;
        second[k][j] = e < 32 ? j : 16 + (e - 32);
      }
    }
  }
};
constexpr XyzPermutes kXyz{};

inline __m512 load_component(const __m512 a, const __m512 b, const __m512 c, int k) {
  const __m512 t = _mm512_permutex2var_ps(a, _mm512_load_si512(kXyz.first[k]), b);
  return _mm512_permutex2var_ps(t, _mm512_load_si512(kXyz.second[k]), c);
}

// The 8 corner rows, weights and fractions of 16 points (x: 48 floats). Returns false when a dense
// index needs a true modulo (inputs far outside [0,1]); the caller then uses the scalar path.
template <bool kDense>
inline bool locate16(const float* x, const Level& lv, __m512i idx[8], __m512 w[8], __m512 frac[3]) {
  const __m512 a = _mm512_loadu_ps(x), b = _mm512_loadu_ps(x + 16), c = _mm512_loadu_ps(x + 32);
  const __m512 scale = _mm512_set1_ps(lv.scale), half = _mm512_set1_ps(0.5f);
  __m512i g[3];
  for (int k = 0; k < 3; ++k) {
    const __m512 pos = _mm512_fmadd_ps(load_component(a, b, c, k), scale, half);
    const __m512 fl = _mm512_roundscale_ps(pos, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
    g[k] = _mm512_cvttps_epi32(fl);
    frac[k] = _mm512_sub_ps(pos, fl);
  }
  bool ok = true;
  if (kDense) {
    const __m512i res = _mm512_set1_epi32(static_cast<int>(lv.res));
    const __m512i res2 = _mm512_set1_epi32(static_cast<int>(lv.res2));
    const __m512i size = _mm512_set1_epi32(static_cast<int>(lv.size));
    const __m512i size2 = _mm512_set1_epi32(static_cast<int>(2 * lv.size));
    const __m512i base = _mm512_add_epi32(
        g[0], _mm512_add_epi32(_mm512_mullo_epi32(g[1], res), _mm512_mullo_epi32(g[2], res2)));
    const uint32_t off[8] = {0u,      1u,          lv.res,           lv.res + 1u,
                             lv.res2, lv.res2 + 1, lv.res2 + lv.res, lv.res2 + lv.res + 1u};
    __mmask16 far = 0;
    for (int k = 0; k < 8; ++k) {
      const __m512i v = _mm512_add_epi32(base, _mm512_set1_epi32(static_cast<int>(off[k])));
      far |= _mm512_cmpge_epu32_mask(v, size2);
      idx[k] = _mm512_mask_sub_epi32(v, _mm512_cmpge_epu32_mask(v, size), v, size);
    }
    ok = far == 0;
  } else {
    const __m512i py = _mm512_set1_epi32(static_cast<int>(kPrimeY));
    const __m512i pz = _mm512_set1_epi32(static_cast<int>(kPrimeZ));
    const __m512i mask = _mm512_set1_epi32(static_cast<int>(lv.mask));
    const __m512i hx[2] = {g[0], _mm512_add_epi32(g[0], _mm512_set1_epi32(1))};
    const __m512i hy0 = _mm512_mullo_epi32(g[1], py), hz0 = _mm512_mullo_epi32(g[2], pz);
    const __m512i hy[2] = {hy0, _mm512_add_epi32(hy0, py)};
    const __m512i hz[2] = {hz0, _mm512_add_epi32(hz0, pz)};
    for (int k = 0; k < 8; ++k) {
      idx[k] = _mm512_and_si512(
          _mm512_xor_si512(_mm512_xor_si512(hx[k & 1], hy[(k >> 1) & 1]), hz[k >> 2]), mask);
    }
  }
  const __m512 one = _mm512_set1_ps(1.0f);
  const __m512 wx[2] = {_mm512_sub_ps(one, frac[0]), frac[0]};
  const __m512 wy[2] = {_mm512_sub_ps(one, frac[1]), frac[1]};
  const __m512 wz[2] = {_mm512_sub_ps(one, frac[2]), frac[2]};
  for (int k = 0; k < 8; ++k) {
    w[k] = _mm512_mul_ps(_mm512_mul_ps(wx[k & 1], wy[(k >> 1) & 1]), wz[k >> 2]);
  }
  return ok;
}

// Gathers the (f0, f1) pairs of 16 rows as two vectors of 8 interleaved pairs.
inline void gather_pairs(const float* table, __m512i idx, __m512& lo, __m512& hi) {
  lo = _mm512_castsi512_ps(_mm512_i32gather_epi64(_mm512_castsi512_si256(idx), table, 8));
  hi = _mm512_castsi512_ps(_mm512_i32gather_epi64(_mm512_extracti64x4_epi64(idx, 1), table, 8));
}

// Lane j of a 16-vector repeated twice: lanes (0,0,1,1,...,7,7) and (8,8,...,15,15).
inline __m512 spread_lo(__m512 v) {
  return _mm512_permutexvar_ps(_mm512_set_epi32(7, 7, 6, 6, 5, 5, 4, 4, 3, 3, 2, 2, 1, 1, 0, 0), v);
}
inline __m512 spread_hi(__m512 v) {
  return _mm512_permutexvar_ps(
      _mm512_set_epi32(15, 15, 14, 14, 13, 13, 12, 12, 11, 11, 10, 10, 9, 9, 8, 8), v);
}

template <bool kDense>
void forward_level_avx512(const float* x, int64_t begin, int64_t end, const float* table,
                          const Level& lv, float* out_level) {
  int64_t i = begin;
  for (; i + 16 <= end; i += 16) {
    __m512i idx[8];
    __m512 w[8], frac[3];
    if (!locate16<kDense>(x + 3 * i, lv, idx, w, frac)) {
      forward_level_scalar<float, 2, kDense>(x, i, i + 16, table, lv, out_level);
      continue;
    }
    __m512 acc_lo = _mm512_setzero_ps(), acc_hi = _mm512_setzero_ps();
    for (int k = 0; k < 8; ++k) {
      __m512 v_lo, v_hi;
      gather_pairs(table, idx[k], v_lo, v_hi);
      acc_lo = _mm512_fmadd_ps(spread_lo(w[k]), v_lo, acc_lo);
      acc_hi = _mm512_fmadd_ps(spread_hi(w[k]), v_hi, acc_hi);
    }
    _mm512_storeu_ps(out_level + 2 * i, acc_lo);
    _mm512_storeu_ps(out_level + 2 * i + 16, acc_hi);
  }
  forward_level_scalar<float, 2, kDense>(x, i, end, table, lv, out_level);
}

// One block of 16 points between its preparation and its scatter.
struct ScatterBlock {
  alignas(64) uint32_t idx[8][16];
  alignas(64) float w[8][16];
  bool simd = false;  // false: the block is handled by the scalar code at its turn
};

template <bool kDense>
void scatter_level_avx512(const float* x, int64_t begin, int64_t end, const float* grad_level,
                          const Level& lv, float* grad_table) {
  // Software pipeline: block b + kAhead is located and its gradient rows prefetched for writing
  // while block b is scattered. The scatter is a read-modify-write of random rows; without the
  // prefetch the store queue fills up behind cache misses.
  constexpr int kAhead = 2;
  ScatterBlock ring[kAhead + 1];
  const int64_t n_blocks = (end - begin) / 16;

  auto prepare = [&](int64_t b, ScatterBlock& blk) {
    __m512i idx[8];
    __m512 w[8], frac[3];
    blk.simd = locate16<kDense>(x + 3 * (begin + 16 * b), lv, idx, w, frac);
    if (!blk.simd) return;
    for (int k = 0; k < 8; ++k) {
      _mm512_store_si512(blk.idx[k], idx[k]);
      _mm512_store_ps(blk.w[k], w[k]);
    }
    for (int k = 0; k < 8; ++k) {
      for (int j = 0; j < 16; ++j) {
        __builtin_prefetch(grad_table + 2 * static_cast<int64_t>(blk.idx[k][j]), 1, 3);
      }
    }
  };

  for (int64_t b = 0; b < std::min<int64_t>(kAhead, n_blocks); ++b) prepare(b, ring[b]);
  for (int64_t b = 0; b < n_blocks; ++b) {
    if (b + kAhead < n_blocks) prepare(b + kAhead, ring[(b + kAhead) % (kAhead + 1)]);
    const ScatterBlock& blk = ring[b % (kAhead + 1)];
    const int64_t i = begin + 16 * b;
    if (!blk.simd) {
      scatter_level_scalar<float, 2, kDense>(x, i, i + 16, grad_level, lv, grad_table);
      continue;
    }
    // The scatter stays scalar and in point order: that order makes the sums deterministic (and
    // identical to the scalar path).
    for (int j = 0; j < 16; ++j) {
      const float* g = grad_level + 2 * (i + j);
      for (int k = 0; k < 8; ++k) {
        float* dst = grad_table + 2 * static_cast<int64_t>(blk.idx[k][j]);
        dst[0] = std::fma(blk.w[k][j], g[0], dst[0]);
        dst[1] = std::fma(blk.w[k][j], g[1], dst[1]);
      }
    }
  }
  scatter_level_scalar<float, 2, kDense>(x, begin + 16 * n_blocks, end, grad_level, lv, grad_table);
}

// Same operation sequence as grad_x_level_scalar, 16 points at a time.
template <bool kDense>
void grad_x_level_avx512(const float* x, int64_t begin, int64_t end, const float* table,
                         const float* grad_level, const Level& lv, bool first, float* grad_x) {
  const __m512i even = _mm512_set_epi32(30, 28, 26, 24, 22, 20, 18, 16, 14, 12, 10, 8, 6, 4, 2, 0);
  const __m512 one = _mm512_set1_ps(1.0f);
  const __m512 scale = _mm512_set1_ps(lv.scale);
  int64_t i = begin;
  for (; i + 16 <= end; i += 16) {
    __m512i idx[8];
    __m512 w[8], frac[3];
    if (!locate16<kDense>(x + 3 * i, lv, idx, w, frac)) {
      grad_x_level_scalar<float, 2, kDense>(x, i, i + 16, table, grad_level, lv, first, grad_x);
      continue;
    }
    const __m512 g_lo = _mm512_loadu_ps(grad_level + 2 * i);
    const __m512 g_hi = _mm512_loadu_ps(grad_level + 2 * i + 16);
    const __m512 g_lo_sw = _mm512_permute_ps(g_lo, 0xB1);
    const __m512 g_hi_sw = _mm512_permute_ps(g_hi, 0xB1);
    const __m512 wx[2] = {_mm512_sub_ps(one, frac[0]), frac[0]};
    const __m512 wy[2] = {_mm512_sub_ps(one, frac[1]), frac[1]};
    const __m512 wz[2] = {_mm512_sub_ps(one, frac[2]), frac[2]};
    __m512 d[3] = {_mm512_setzero_ps(), _mm512_setzero_ps(), _mm512_setzero_ps()};
    for (int k = 0; k < 8; ++k) {
      __m512 v_lo, v_hi;
      gather_pairs(table, idx[k], v_lo, v_hi);
      // Even lanes: fma(g1, v1, g0 · v0).
      const __m512 s_lo =
          _mm512_fmadd_ps(g_lo_sw, _mm512_permute_ps(v_lo, 0xB1), _mm512_mul_ps(g_lo, v_lo));
      const __m512 s_hi =
          _mm512_fmadd_ps(g_hi_sw, _mm512_permute_ps(v_hi, 0xB1), _mm512_mul_ps(g_hi, v_hi));
      const __m512 gv = _mm512_permutex2var_ps(s_lo, even, s_hi);
      const int bx = k & 1, by = (k >> 1) & 1, bz = k >> 2;
      const __m512 tyz = _mm512_mul_ps(wy[by], wz[bz]);
      const __m512 txz = _mm512_mul_ps(wx[bx], wz[bz]);
      const __m512 txy = _mm512_mul_ps(wx[bx], wy[by]);
      d[0] = bx ? _mm512_fmadd_ps(tyz, gv, d[0]) : _mm512_fnmadd_ps(tyz, gv, d[0]);
      d[1] = by ? _mm512_fmadd_ps(txz, gv, d[1]) : _mm512_fnmadd_ps(txz, gv, d[1]);
      d[2] = bz ? _mm512_fmadd_ps(txy, gv, d[2]) : _mm512_fnmadd_ps(txy, gv, d[2]);
    }
    // Interleave the three component vectors back to 16 xyz triples.
    alignas(64) float d_s[3][16];
    float* gx = grad_x + 3 * i;
    if (first) {
      for (int k = 0; k < 3; ++k) _mm512_store_ps(d_s[k], _mm512_mul_ps(scale, d[k]));
      for (int j = 0; j < 16; ++j) {
        for (int k = 0; k < 3; ++k) gx[3 * j + k] = d_s[k][j];
      }
    } else {
      for (int k = 0; k < 3; ++k) _mm512_store_ps(d_s[k], d[k]);
      for (int j = 0; j < 16; ++j) {
        for (int k = 0; k < 3; ++k) gx[3 * j + k] = std::fma(lv.scale, d_s[k][j], gx[3 * j + k]);
      }
    }
  }
  grad_x_level_scalar<float, 2, kDense>(x, i, end, table, grad_level, lv, first, grad_x);
}
#endif  // NERAF_HASH_GRID_AVX512

// Dispatch of one level's forward / backward to the best available path.
template <typename T, int F, bool kDense>
void forward_level(const T* x, int64_t begin, int64_t end, const T* table, const Level& lv,
                   T* out_level, bool simd) {
#if NERAF_HASH_GRID_AVX512
  if constexpr (std::is_same_v<T, float> && F == 2) {
    if (simd) return forward_level_avx512<kDense>(x, begin, end, table, lv, out_level);
  }
#endif
  forward_level_scalar<T, F, kDense>(x, begin, end, table, lv, out_level);
}

template <typename T, int F, bool kDense>
void scatter_level(const T* x, int64_t n, const T* grad_level, const Level& lv, T* grad_table,
                   bool simd) {
#if NERAF_HASH_GRID_AVX512
  if constexpr (std::is_same_v<T, float> && F == 2) {
    if (simd) return scatter_level_avx512<kDense>(x, 0, n, grad_level, lv, grad_table);
  }
#endif
  scatter_level_scalar<T, F, kDense>(x, 0, n, grad_level, lv, grad_table);
}

template <typename T, int F, bool kDense>
void grad_x_level(const T* x, int64_t begin, int64_t end, const T* table, const T* grad_level,
                  const Level& lv, bool first, T* grad_x, bool simd) {
#if NERAF_HASH_GRID_AVX512
  if constexpr (std::is_same_v<T, float> && F == 2) {
    if (simd) {
      return grad_x_level_avx512<kDense>(x, begin, end, table, grad_level, lv, first, grad_x);
    }
  }
#endif
  grad_x_level_scalar<T, F, kDense>(x, begin, end, table, grad_level, lv, first, grad_x);
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
                  int num_threads, bool simd) {
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
        forward_level<T, F, true>(x, begin, end, tl, lv, ol, simd);
      } else {
        forward_level<T, F, false>(x, begin, end, tl, lv, ol, simd);
      }
      // Keep the threads on the same level so that only one level's table is hot at a time.
#pragma omp barrier
    }
  }
  level_major_to_point_major<T, F>(scratch.get(), n, L, out, nt);
}

template <typename T, int F>
void backward_impl(const T* x, int64_t n, const T* table, const T* grad_out,
                   const HashGridLayout& layout, T* grad_table, T* grad_x, int num_threads,
                   bool simd) {
  const int L = layout.num_levels();
  const int nt = threads_for(n, num_threads);
  std::unique_ptr<T[]> grad_lm(new T[static_cast<size_t>(n) * L * F]);
  point_major_to_level_major<T, F>(grad_out, n, L, grad_lm.get(), nt);

  // Table gradient. Each level is owned by exactly one thread and accumulated in point order, so
  // the result does not depend on which thread takes it: dynamic scheduling (finest, most
  // expensive levels first) balances the load without costing determinism.
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::min(nt, L))
  for (int k = 0; k < L; ++k) {
    const int l = L - 1 - k;
    const Level lv = level_of(layout, l);
    const int64_t off = layout.offsets[l] * F;
    const T* gl = grad_lm.get() + static_cast<int64_t>(l) * n * F;
    // Zeroing the level's slice right before its scatter leaves it in cache for the scatter's
    // read-modify-writes (one pass over the whole 48 MB table beforehand would not).
    std::fill_n(grad_table + off, layout.sizes[l] * F, T(0));
    if (layout.dense[l]) {
      scatter_level<T, F, true>(x, n, gl, lv, grad_table + off, simd);
    } else {
      scatter_level<T, F, false>(x, n, gl, lv, grad_table + off, simd);
    }
  }
  if (grad_x == nullptr) return;

    // Position gradient: like the forward pass (level-outer, points split across threads), summed
    // over levels in level order, so again independent of the thread count.
#pragma omp parallel num_threads(nt)
  {
    const int tid = omp_get_thread_num(), nth = omp_get_num_threads();
    const int64_t begin = n * tid / nth, end = n * (tid + 1) / nth;
    for (int l = 0; l < L; ++l) {
      const Level lv = level_of(layout, l);
      const T* tl = table + layout.offsets[l] * F;
      const T* gl = grad_lm.get() + static_cast<int64_t>(l) * n * F;
      if (layout.dense[l]) {
        grad_x_level<T, F, true>(x, begin, end, tl, gl, lv, l == 0, grad_x, simd);
      } else {
        grad_x_level<T, F, false>(x, begin, end, tl, gl, lv, l == 0, grad_x, simd);
      }
#pragma omp barrier
    }
  }
}

}  // namespace

bool hash_grid_has_simd() { return NERAF_HASH_GRID_AVX512 != 0; }

template <typename T>
void hash_grid_forward_cpu(const T* x, int64_t n, const T* table, const HashGridLayout& layout,
                           T* out, int num_threads, HashGridPath path) {
  if (n <= 0) return;
  const bool simd = path == HashGridPath::kBest;
  switch (layout.features()) {
    case 1:
      return forward_impl<T, 1>(x, n, table, layout, out, num_threads, simd);
    case 2:
      return forward_impl<T, 2>(x, n, table, layout, out, num_threads, simd);
    case 4:
      return forward_impl<T, 4>(x, n, table, layout, out, num_threads, simd);
    case 8:
      return forward_impl<T, 8>(x, n, table, layout, out, num_threads, simd);
  }
}

template <typename T>
void hash_grid_backward_cpu(const T* x, int64_t n, const T* table, const T* grad_out,
                            const HashGridLayout& layout, T* grad_table, T* grad_x, int num_threads,
                            HashGridPath path) {
  if (n <= 0) {
    std::fill_n(grad_table, layout.num_parameters(), T(0));
    return;
  }
  const bool simd = path == HashGridPath::kBest;
  switch (layout.features()) {
    case 1:
      return backward_impl<T, 1>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads,
                                 simd);
    case 2:
      return backward_impl<T, 2>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads,
                                 simd);
    case 4:
      return backward_impl<T, 4>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads,
                                 simd);
    case 8:
      return backward_impl<T, 8>(x, n, table, grad_out, layout, grad_table, grad_x, num_threads,
                                 simd);
  }
}

template void hash_grid_forward_cpu<float>(const float*, int64_t, const float*,
                                           const HashGridLayout&, float*, int, HashGridPath);
template void hash_grid_forward_cpu<double>(const double*, int64_t, const double*,
                                            const HashGridLayout&, double*, int, HashGridPath);
template void hash_grid_backward_cpu<float>(const float*, int64_t, const float*, const float*,
                                            const HashGridLayout&, float*, float*, int,
                                            HashGridPath);
template void hash_grid_backward_cpu<double>(const double*, int64_t, const double*, const double*,
                                             const HashGridLayout&, double*, double*, int,
                                             HashGridPath);

}  // namespace neraf::nerf
