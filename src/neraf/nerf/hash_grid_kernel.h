#pragma once
// Multiresolution hash encoding (Instant-NGP), tiny-cuda-nn semantics, as plain CPU kernels over
// raw pointers: no LibTorch here, so the kernels can be unit-tested and benchmarked on their own.
// The autograd op and the nn::Module live in hash_grid.h.
//
// Semantics (tiny-cuda-nn `GridEncoding`, grid type Hash, linear interpolation), all in float32:
//   per_level_scale = (float) exp((ln max_res − ln base_res) / (L − 1))  (what nerfstudio passes)
//   scale_l = exp2(l · log2(per_level_scale)) · base_res − 1
//   res_l   = ceil(scale_l) + 1
//   size_l  = min(next_multiple_of_8(res_l³), 2^log2_hashmap_size)   (table rows of level l)
//   pos     = fma(x, scale_l, 0.5); grid = floor(pos); frac = pos − grid (trilinear weights)
//   corner index: dense levels (res_l³ ≤ size_l): x + y·res + z·res² (uint32 arithmetic) mod size_l
//                 (the +0.5 offset may wrap the top corner around, as in tcnn: harmless);
//                 hashed levels: (x·1 ⊕ y·2654435761 ⊕ z·805459861) mod size_l (uint32 products).
// Inputs outside [0,1] follow the same uint32 wrap-around as tcnn (no clamping); contracted
// Nerfacto coordinates are always inside [0,1].
// The table is [total_entries, F] row-major: the F features of one entry are contiguous.
// The output is [N, L·F] row-major, level-major within a point (what the MLP consumes).
#include <cstdint>
#include <vector>

namespace neraf::nerf {

struct HashGridConfig {
  int num_levels = 16;         // L
  int features_per_level = 2;  // F: 1, 2, 4 or 8
  int log2_hashmap_size = 19;  // T = 2^19 rows per hashed level
  int base_resolution = 16;    // vertices per side of level 0 (tcnn: scale_0 = base − 1)
  int max_resolution = 2048;   // only used to derive per_level_scale, as nerfstudio does
};

// Everything the kernels need to know about the table, derived once from a config.
struct HashGridLayout {
  HashGridConfig config;
  float per_level_scale = 1.0f;      // growth factor, float as tcnn stores it
  std::vector<int64_t> offsets;      // [L + 1] first table row of each level; back() = total
  std::vector<int64_t> sizes;        // [L] table rows of each level
  std::vector<float> scales;         // [L] scale_l
  std::vector<int64_t> resolutions;  // [L] res_l (vertices per side)
  std::vector<uint8_t> dense;        // [L] 1: dense row-major level, 0: hashed level
  int64_t total_entries = 0;         // table rows = Σ sizes (6,098,120 for the Nerfacto default)

  int num_levels() const { return config.num_levels; }
  int features() const { return config.features_per_level; }
  int output_dim() const { return config.num_levels * config.features_per_level; }  // L·F
  int64_t num_parameters() const { return total_entries * config.features_per_level; }

  // Throws neraf::Error naming the offending field when the config is invalid.
  static HashGridLayout make(const HashGridConfig& config);
};

// Which code path the kernels take. kBest uses AVX-512 for float32 with F = 2 when the build
// targets it (-march=native on an AVX-512 machine) and the portable scalar code otherwise; the two
// paths produce bit-identical results (the tests check it). kScalar forces the portable code.
enum class HashGridPath { kBest, kScalar };

// True when this build contains the AVX-512 path.
bool hash_grid_has_simd();

// All kernels: x is [n, 3] row-major; num_threads ≥ 1 OpenMP threads. Deterministic: the result
// bits do not depend on num_threads (nor on the path).

// out: [n, L·F], fully overwritten. Level-outer, point-inner (one level's table stays hot in
// cache), points split across threads within a level.
template <typename T>
void hash_grid_forward_cpu(const T* x, int64_t n, const T* table, const HashGridLayout& layout,
                           T* out, int num_threads, HashGridPath path = HashGridPath::kBest);

// Gradient w.r.t. the table, written to grad_table ([total_entries, F], fully overwritten: each
// level's slice is zeroed by its owner thread just before use). grad_out: [n, L·F]. Levels are
// owned by threads (no atomics); within a level points are accumulated in index order, so the bits
// do not depend on num_threads. With 2 threads and 16 levels each thread owns 8 levels; there is no
// parallelism beyond L threads. If grad_x is not null ([n, 3], overwritten) the gradient w.r.t. x
// is computed too, in a second pass shaped like the forward one (needs `table`, which may be null
// otherwise; summed over levels in level order, also thread-count independent). It costs about one
// more forward pass.
template <typename T>
void hash_grid_backward_cpu(const T* x, int64_t n, const T* table, const T* grad_out,
                            const HashGridLayout& layout, T* grad_table, T* grad_x, int num_threads,
                            HashGridPath path = HashGridPath::kBest);

}  // namespace neraf::nerf
