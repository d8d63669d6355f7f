#include "neraf/runtime/bf16_gemm.h"

#include <cstring>
#include <stdexcept>
#include <string>

#include "neraf/runtime/model_file.h"

#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__))
#define NERAF_RT_X86 1
#include <cpuid.h>
#include <immintrin.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace neraf::rt {

namespace {

#ifdef NERAF_RT_X86
// The palette-1 tile configuration: tiles 0-3 accumulate a 2×2 block of results, 4-5 hold two
// row blocks of X, 6-7 two column blocks of W; all 16 rows × 64 bytes.
struct alignas(64) TileConfig {
  uint8_t palette = 1;
  uint8_t start_row = 0;
  uint8_t reserved[14] = {};
  uint16_t colsb[16] = {};
  uint8_t rows[16] = {};
};

uint64_t xgetbv0() {
  uint32_t lo, hi;
  __asm__ volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
  return uint64_t(hi) << 32 | lo;
}

bool os_saves_avx_state() {
  unsigned a, b, c, d;
  return __get_cpuid(1, &a, &b, &c, &d) && (c & (1u << 27));  // OSXSAVE: xgetbv is there
}

bool detect_avx512_bf16() {
  unsigned a, b, c, d;
  if (!os_saves_avx_state()) return false;
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d) || !(b & (1u << 16))) return false;  // AVX512F
  if (!__get_cpuid_count(7, 1, &a, &b, &c, &d) || !(a & (1u << 5))) return false;   // AVX512_BF16
  return (xgetbv0() & 0xE6) == 0xE6;  // SSE, AVX, opmask and both halves of the zmm state
}

bool detect_amx() {
  unsigned a, b, c, d;
  if (!os_saves_avx_state()) return false;
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return false;
  const bool amx_bf16 = d & (1u << 22), amx_tile = d & (1u << 24);
  if (!amx_bf16 || !amx_tile) return false;
  if ((xgetbv0() & (3ull << 17)) != (3ull << 17)) return false;  // XTILECFG, XTILEDATA enabled
  // Linux (5.16+) allocates the 8 KiB tile state only for processes that ask.
  constexpr int kArchReqXcompPerm = 0x1023, kXfeatureXtiledata = 18;
  return syscall(SYS_arch_prctl, kArchReqXcompPerm, kXfeatureXtiledata) == 0;
}

// One 2×2 (or 1×2 for a last odd row block) block of result tiles over the whole depth.
__attribute__((target("amx-tile,amx-bf16"))) void amx_kernel(const uint16_t* x, int row_blocks,
                                                             int k_blocks, const uint16_t* w,
                                                             int n_padded, float* y, int jb_begin,
                                                             int jb_end) {
  constexpr size_t kTile = 512;  // bf16 values per tile
  const long y_stride = long(n_padded) * 4;
  for (int ib = 0; ib < row_blocks; ib += 2) {
    const bool two_rows = ib + 1 < row_blocks;
    const uint16_t* a0 = x + size_t(ib) * k_blocks * kTile;
    const uint16_t* a1 = a0 + size_t(k_blocks) * kTile;
    for (int jb = jb_begin; jb < jb_end; jb += 2) {
      const uint16_t* b0 = w + size_t(jb) * k_blocks * kTile;
      const uint16_t* b1 = b0 + size_t(k_blocks) * kTile;
      _tile_zero(0);
      _tile_zero(1);
      _tile_zero(2);
      _tile_zero(3);
      for (int kb = 0; kb < k_blocks; ++kb) {
        _tile_loadd(4, a0 + kb * kTile, 64);
        _tile_loadd(6, b0 + kb * kTile, 64);
        _tile_loadd(7, b1 + kb * kTile, 64);
        _tile_dpbf16ps(0, 4, 6);
        _tile_dpbf16ps(1, 4, 7);
        if (two_rows) {
          _tile_loadd(5, a1 + kb * kTile, 64);
          _tile_dpbf16ps(2, 5, 6);
          _tile_dpbf16ps(3, 5, 7);
        }
      }
      float* c = y + size_t(ib) * kTileRows * n_padded + size_t(jb) * kTileColumns;
      _tile_stored(0, c, y_stride);
      _tile_stored(1, c + kTileColumns, y_stride);
      if (two_rows) {
        _tile_stored(2, c + size_t(kTileRows) * n_padded, y_stride);
        _tile_stored(3, c + size_t(kTileRows) * n_padded + kTileColumns, y_stride);
      }
    }
  }
}

// Column blocks [jb_begin, jb_end) in pairs; per pair, every 8 rows [ib·16 + 8·half, +8) of the
// result over the whole depth: 8 rows × 2 column blocks of 16 = 16 accumulators of 16 floats. Per
// k-pair, a row of each B tile is one VDPBF16PS operand (16 columns × the pair) and each row's
// pair of A is broadcast to all 16 lanes. Pairs outermost: a pair's weights (K × 32 bf16) come
// from memory once and stay in cache over all rows, and the activations (T × K, T ≤ a few hundred)
// are what is re-read. Rows outermost would re-read the whole weight matrix for every 8 rows:
// from memory, for the `paper` preset's 2048 × 5096 layer (20 MB in bf16).
__attribute__((target("avx512f,avx512bf16"))) void avx512_bf16_kernel(const uint16_t* x,
                                                                      int row_blocks, int k_blocks,
                                                                      const uint16_t* w,
                                                                      int n_padded, float* y,
                                                                      int jb_begin, int jb_end) {
  constexpr size_t kTile = 512;  // bf16 values per tile
  constexpr int kRows = 8;
  for (int jb = jb_begin; jb < jb_end; jb += 2) {
    const uint16_t* b0 = w + size_t(jb) * k_blocks * kTile;
    const uint16_t* b1 = b0 + size_t(k_blocks) * kTile;
    for (int ib = 0; ib < row_blocks; ++ib)
      for (int half = 0; half < 2; ++half) {
        const uint16_t* a = x + size_t(ib) * k_blocks * kTile + half * kRows * kTileDepth;
        __m512 acc0[kRows], acc1[kRows];
#pragma GCC unroll 8
        for (int r = 0; r < kRows; ++r) acc0[r] = acc1[r] = _mm512_setzero_ps();
        for (int kb = 0; kb < k_blocks; ++kb) {
          const uint16_t* at = a + kb * kTile;
          const uint16_t* bt0 = b0 + kb * kTile;
          const uint16_t* bt1 = b1 + kb * kTile;
          for (int kp = 0; kp < kTileDepth / 2; ++kp) {
            const __m512bh w0 = (__m512bh)_mm512_loadu_si512(bt0 + kp * 2 * kTileColumns);
            const __m512bh w1 = (__m512bh)_mm512_loadu_si512(bt1 + kp * 2 * kTileColumns);
#pragma GCC unroll 8
            for (int r = 0; r < kRows; ++r) {
              int32_t pair;
              std::memcpy(&pair, at + r * kTileDepth + 2 * kp, sizeof pair);
              const __m512bh xr = (__m512bh)_mm512_set1_epi32(pair);
              acc0[r] = _mm512_dpbf16_ps(acc0[r], xr, w0);
              acc1[r] = _mm512_dpbf16_ps(acc1[r], xr, w1);
            }
          }
        }
        float* c =
            y + (size_t(ib) * kTileRows + half * kRows) * n_padded + size_t(jb) * kTileColumns;
#pragma GCC unroll 8
        for (int r = 0; r < kRows; ++r) {
          _mm512_storeu_ps(c + size_t(r) * n_padded, acc0[r]);
          _mm512_storeu_ps(c + size_t(r) * n_padded + kTileColumns, acc1[r]);
        }
      }
  }
}

__attribute__((target("amx-tile"))) void load_tile_config() {
  TileConfig cfg;
  for (int t = 0; t < 8; ++t) {
    cfg.rows[t] = kTileRows;
    cfg.colsb[t] = 64;
  }
  // GCC 12 does not model ldtilecfg's read of `cfg`: without this barrier it drops the stores
  // above as dead (seen without -march=native), and the garbage configuration faults.
  __asm__ volatile("" : : "r"(&cfg) : "memory");
  _tile_loadconfig(&cfg);
}

__attribute__((target("amx-tile"))) void release_tiles() { _tile_release(); }
#endif

}  // namespace

Bf16Kernel best_bf16_kernel() {
#ifdef NERAF_RT_X86
  static const Bf16Kernel best = detect_amx()           ? Bf16Kernel::amx
                                 : detect_avx512_bf16() ? Bf16Kernel::avx512
                                                        : Bf16Kernel::none;
  return best;
#else
  return Bf16Kernel::none;
#endif
}

bool bf16_kernel_available(Bf16Kernel kernel) {
#ifdef NERAF_RT_X86
  switch (kernel) {
    case Bf16Kernel::amx:
      return best_bf16_kernel() == Bf16Kernel::amx;
    case Bf16Kernel::avx512: {
      static const bool avx512 = detect_avx512_bf16();
      return avx512;
    }
    case Bf16Kernel::none:
      break;
  }
#else
  (void)kernel;
#endif
  return false;
}

const char* bf16_kernel_name(Bf16Kernel kernel) {
  switch (kernel) {
    case Bf16Kernel::amx:
      return "amx";
    case Bf16Kernel::avx512:
      return "avx512";
    case Bf16Kernel::none:
      break;
  }
  return "none";
}

Bf16Matrix::Bf16Matrix(const float* weight, int out, int in, Bf16Kernel kernel)
    : in_(in),
      out_(out),
      in_padded_(round_up(in, kTileDepth)),
      out_padded_(round_up(out, 32)),
      kernel_(kernel) {
  if (!bf16_kernel_available(kernel))
    throw std::invalid_argument(std::string("Bf16Matrix: the ") + bf16_kernel_name(kernel) +
                                " kernel cannot run in this process");
  const int kb_count = in_padded_ / kTileDepth;
  tiles_.assign(size_t(out_padded_) * in_padded_, 0);
  for (int jb = 0; jb < out_padded_ / kTileColumns; ++jb)
    for (int kb = 0; kb < kb_count; ++kb) {
      uint16_t* tile = tiles_.data() + (size_t(jb) * kb_count + kb) * 512;
      for (int kp = 0; kp < kTileDepth / 2; ++kp)
        for (int n = 0; n < kTileColumns; ++n)
          for (int e = 0; e < 2; ++e) {
            const int row = jb * kTileColumns + n, col = kb * kTileDepth + 2 * kp + e;
            if (row < out && col < in)
              tile[(kp * kTileColumns + n) * 2 + e] = float_to_bf16(weight[size_t(row) * in + col]);
          }
    }
}

void Bf16Matrix::multiply(const uint16_t* x_tiles, int m, float* y, int n_begin, int n_end) const {
#ifdef NERAF_RT_X86
  const int row_blocks = m / kTileRows, k_blocks = in_padded_ / kTileDepth;
  const int jb_begin = n_begin / kTileColumns, jb_end = n_end / kTileColumns;
  if (kernel_ == Bf16Kernel::amx) {
    load_tile_config();
    amx_kernel(x_tiles, row_blocks, k_blocks, tiles_.data(), out_padded_, y, jb_begin, jb_end);
    release_tiles();  // the OS then need not save 8 KiB of tile state at each context switch
  } else if (kernel_ == Bf16Kernel::avx512) {
    avx512_bf16_kernel(x_tiles, row_blocks, k_blocks, tiles_.data(), out_padded_, y, jb_begin,
                       jb_end);
  }
#else
  (void)x_tiles, (void)m, (void)y, (void)n_begin, (void)n_end;
#endif
}

void pack_activations(const float* x, int rows, int cols, size_t ld, int m_padded, int k_padded,
                      uint16_t* out) {
  const int kb_count = k_padded / kTileDepth;
  for (int ib = 0; ib < m_padded / kTileRows; ++ib)
    for (int kb = 0; kb < kb_count; ++kb) {
      uint16_t* tile = out + (size_t(ib) * kb_count + kb) * 512;
      for (int r = 0; r < kTileRows; ++r) {
        const int row = ib * kTileRows + r;
        const int col0 = kb * kTileDepth;
        uint16_t* dst = tile + r * kTileDepth;
        if (row < rows && col0 + kTileDepth <= cols) {
          const float* src = x + size_t(row) * ld + col0;
          for (int c = 0; c < kTileDepth; ++c) dst[c] = float_to_bf16(src[c]);
        } else {
          for (int c = 0; c < kTileDepth; ++c)
            dst[c] =
                (row < rows && col0 + c < cols) ? float_to_bf16(x[size_t(row) * ld + col0 + c]) : 0;
        }
      }
    }
}

}  // namespace neraf::rt
