#pragma once
// bfloat16 matrix products for the trunk and heads of models exported in bfloat16: Y = X·Wᵀ with X
// and W rounded to bfloat16, products accumulated in float32. Two kernels on the same packed
// layouts:
//   amx     Intel AMX tiles (TDPBF16PS; Sapphire Rapids and later), ~15× the float32 throughput
//           of AVX-512 FMA on one core;
//   avx512  AVX512-BF16 (VDPBF16PS; Cooper Lake, AMD Zen 4 and later), a pair of products per
//           float32 lane: ~2× the float32 FMA throughput.
// Each result is computed the same way whatever the split of the columns between threads, so
// results do not depend on the thread count (the two kernels may differ in the last bits).
//
// Layouts (all "tiles" 16 rows × 64 bytes, 1 KiB, contiguous):
//   activations  X [M, K] float32 → A tiles [M/16][K/32][16 rows][32 k] bf16 (pack_activations)
//   weights      W [N, K] float32 → B tiles [N/16][K/32][16 k-pairs][16 n][2] bf16 (Bf16Matrix;
//                the "VNNI" layout both instructions multiply: pairs of k per column, so one
//                row of a B tile is one 512-bit VDPBF16PS operand)
//   result       Y [M, N_padded] float32, row-major
// M is a multiple of 16, K and N are padded to multiples of 32 (zeros), so every tile is full.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace neraf::rt {

enum class Bf16Kernel { none, avx512, amx };

// The fastest bf16 kernel this process may run: amx where the CPU has AMX-BF16, the OS saves the
// tile state and Linux granted the tile data permission (asked once, process-wide); else avx512
// where the CPU has AVX512-BF16 and the OS saves the 512-bit state; else none.
Bf16Kernel best_bf16_kernel();
// Whether this process may run `kernel` (none: always false).
bool bf16_kernel_available(Bf16Kernel kernel);
const char* bf16_kernel_name(Bf16Kernel kernel);  // "none", "avx512", "amx"

constexpr int kTileRows = 16;     // rows of a tile (M granularity)
constexpr int kTileDepth = 32;    // bf16 values per tile row (K granularity)
constexpr int kTileColumns = 16;  // columns of a result tile (N granularity; pairs are computed)

inline int round_up(int n, int m) { return (n + m - 1) / m * m; }

// The weights of one dense layer, packed for the bf16 kernels (immutable, shareable).
class Bf16Matrix {
 public:
  Bf16Matrix() = default;
  // weight: [out, in] row-major; kernel: the one multiply() runs (must be available).
  Bf16Matrix(const float* weight, int out, int in, Bf16Kernel kernel);

  int in() const { return in_; }
  int out() const { return out_; }
  int in_padded() const { return in_padded_; }    // multiple of 32
  int out_padded() const { return out_padded_; }  // multiple of 32
  Bf16Kernel kernel() const { return kernel_; }

  // y[m, out_padded] (columns [n_begin, n_end)) = x · Wᵀ, x packed by pack_activations with
  // in_padded() columns; m a multiple of 16; n_begin, n_end multiples of 32 (a split of the
  // columns between threads). On AMX, loads and releases the calling thread's tile configuration.
  void multiply(const uint16_t* x_tiles, int m, float* y, int n_begin, int n_end) const;

 private:
  int in_ = 0, out_ = 0, in_padded_ = 0, out_padded_ = 0;
  Bf16Kernel kernel_ = Bf16Kernel::none;
  std::vector<uint16_t> tiles_;  // [out_padded/16][in_padded/32][16][16][2]
};

// x [rows, cols] float32 (row stride ld) → A tiles of m_padded rows (a multiple of 16) and
// k_padded columns (a multiple of 32), rounded to bfloat16 (nearest even); the padding is zero.
void pack_activations(const float* x, int rows, int cols, size_t ld, int m_padded, int k_padded,
                      uint16_t* out);

}  // namespace neraf::rt
