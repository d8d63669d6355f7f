#include "neraf/runtime/amx_gemm.h"

#include <cstring>

#include "neraf/runtime/model_file.h"

#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__))
#define NERAF_RT_AMX 1
#include <cpuid.h>
#include <immintrin.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace neraf::rt {

namespace {

#ifdef NERAF_RT_AMX
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

bool detect_amx() {
  unsigned a, b, c, d;
  if (!__get_cpuid(1, &a, &b, &c, &d) || !(c & (1u << 27))) return false;  // OSXSAVE
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
      float* c = y + size_t(ib) * kAmxRows * n_padded + size_t(jb) * kAmxColumns;
      _tile_stored(0, c, y_stride);
      _tile_stored(1, c + kAmxColumns, y_stride);
      if (two_rows) {
        _tile_stored(2, c + size_t(kAmxRows) * n_padded, y_stride);
        _tile_stored(3, c + size_t(kAmxRows) * n_padded + kAmxColumns, y_stride);
      }
    }
  }
}

__attribute__((target("amx-tile"))) void load_tile_config() {
  TileConfig cfg;
  for (int t = 0; t < 8; ++t) {
    cfg.rows[t] = kAmxRows;
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

bool amx_bf16_available() {
#ifdef NERAF_RT_AMX
  static const bool available = detect_amx();
  return available;
#else
  return false;
#endif
}

AmxMatrix::AmxMatrix(const float* weight, int out, int in)
    : in_(in), out_(out), in_padded_(round_up(in, kAmxDepth)), out_padded_(round_up(out, 32)) {
  const int kb_count = in_padded_ / kAmxDepth;
  tiles_.assign(size_t(out_padded_) * in_padded_, 0);
  for (int jb = 0; jb < out_padded_ / kAmxColumns; ++jb)
    for (int kb = 0; kb < kb_count; ++kb) {
      uint16_t* tile = tiles_.data() + (size_t(jb) * kb_count + kb) * 512;
      for (int kp = 0; kp < kAmxDepth / 2; ++kp)
        for (int n = 0; n < kAmxColumns; ++n)
          for (int e = 0; e < 2; ++e) {
            const int row = jb * kAmxColumns + n, col = kb * kAmxDepth + 2 * kp + e;
            if (row < out && col < in)
              tile[(kp * kAmxColumns + n) * 2 + e] = float_to_bf16(weight[size_t(row) * in + col]);
          }
    }
}

void AmxMatrix::multiply(const uint16_t* x_tiles, int m, float* y, int n_begin, int n_end) const {
#ifdef NERAF_RT_AMX
  load_tile_config();
  amx_kernel(x_tiles, m / kAmxRows, in_padded_ / kAmxDepth, tiles_.data(), out_padded_, y,
             n_begin / kAmxColumns, n_end / kAmxColumns);
  release_tiles();  // the OS then need not save 8 KiB of tile state at each context switch
#else
  (void)x_tiles, (void)m, (void)y, (void)n_begin, (void)n_end;
#endif
}

void pack_activations(const float* x, int rows, int cols, size_t ld, int m_padded, int k_padded,
                      uint16_t* out) {
  const int kb_count = k_padded / kAmxDepth;
  for (int ib = 0; ib < m_padded / kAmxRows; ++ib)
    for (int kb = 0; kb < kb_count; ++kb) {
      uint16_t* tile = out + (size_t(ib) * kb_count + kb) * 512;
      for (int r = 0; r < kAmxRows; ++r) {
        const int row = ib * kAmxRows + r;
        const int col0 = kb * kAmxDepth;
        uint16_t* dst = tile + r * kAmxDepth;
        if (row < rows && col0 + kAmxDepth <= cols) {
          const float* src = x + size_t(row) * ld + col0;
          for (int c = 0; c < kAmxDepth; ++c) dst[c] = float_to_bf16(src[c]);
        } else {
          for (int c = 0; c < kAmxDepth; ++c)
            dst[c] =
                (row < rows && col0 + c < cols) ? float_to_bf16(x[size_t(row) * ld + col0 + c]) : 0;
        }
      }
    }
}

}  // namespace neraf::rt
