#pragma once
// bfloat16 matrix products on Intel AMX tiles (Sapphire Rapids and later) for the trunk of models
// exported in bfloat16: Y = X·Wᵀ with X and W rounded to bfloat16, products accumulated in
// float32 (TDPBF16PS), ~15× the float32 throughput of AVX-512 FMA on one core.
//
// Layouts (all tiles 16 rows × 64 bytes, 1 KiB, contiguous):
//   activations  X [M, K] float32 → A tiles [M/16][K/32][16 rows][32 k] bf16 (pack_activations)
//   weights      W [N, K] float32 → B tiles [N/16][K/32][16 k-pairs][16 n][2] bf16 (AmxMatrix;
//                the "VNNI" layout TDPBF16PS multiplies: pairs of k per column)
//   result       Y [M, N_padded] float32, row-major
// M is a multiple of 16, K and N are padded to multiples of 32 (zeros), so every tile is full.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace neraf::rt {

// Whether this process may run AMX-BF16: the CPU has it, the OS saves the tile state and
// Linux granted the tile data permission (asked once, process-wide). False on other systems.
bool amx_bf16_available();

constexpr int kAmxRows = 16;    // rows of a tile (M granularity)
constexpr int kAmxDepth = 32;   // bf16 values per tile row (K granularity)
constexpr int kAmxColumns = 16; // columns of a result tile (N granularity; pairs are computed)

inline int round_up(int n, int m) { return (n + m - 1) / m * m; }

// The weights of one dense layer, packed for the AMX kernel (immutable, shareable).
class AmxMatrix {
 public:
  AmxMatrix() = default;
  AmxMatrix(const float* weight, int out, int in);  // weight: [out, in] row-major

  int in() const { return in_; }
  int out() const { return out_; }
  int in_padded() const { return in_padded_; }    // multiple of 32
  int out_padded() const { return out_padded_; }  // multiple of 32

  // y[m, out_padded] (columns [n_begin, n_end)) = x · Wᵀ, x packed by pack_activations with
  // in_padded() columns; m a multiple of 16; n_begin, n_end multiples of 32 (a split of the
  // columns between threads). Loads and releases the calling thread's tile configuration.
  void multiply(const uint16_t* x_tiles, int m, float* y, int n_begin, int n_end) const;

 private:
  int in_ = 0, out_ = 0, in_padded_ = 0, out_padded_ = 0;
  std::vector<uint16_t> tiles_;  // [out_padded/16][in_padded/32][16][16][2]
};

// x [rows, cols] float32 (row stride ld) → A tiles of m_padded rows (a multiple of 16) and
// k_padded columns (a multiple of 32), rounded to bfloat16 (nearest even); the padding is zero.
void pack_activations(const float* x, int rows, int cols, size_t ld, int m_padded, int k_padded,
                      uint16_t* out);

}  // namespace neraf::rt
