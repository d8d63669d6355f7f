#pragma once
// NeRF-style frequency encoding with the exact semantics of nerfstudio's `NeRFEncoding` (torch
// path), which NeRAF uses for the time index and the microphone/source positions
// (neraf-reference.md §1.2):
//
//   x' = 2π·x;  f_k = 2^(linspace(min_exp, max_exp, n))  (NON-integer exponents: 0, 8/9, 16/9, … 8)
//   s  = x'[..., None] · f, laid out dim-major  (d0f0 … d0f9, d1f0 …, d2f0 …)
//   out = [sin(s), sin(s + π/2), x]   (all sines, then all cosines, then the raw input LAST)
//
// The frequencies are computed the way the reference computes them (linspace and power in float32,
// then promoted to the input's dtype), so a float64 input reproduces the reference bit for bit up
// to libm differences. The computation runs in the input's dtype: NeRAF's dataset tensors are
// float64, so callers encode positions in float64 and cast the concatenated features to float32
// afterwards.
#include <torch/types.h>

#include <cstdint>

namespace neraf::acoustic {

struct NerfEncodingOptions {
  int64_t in_dim = 3;
  int64_t num_frequencies = 10;
  double min_freq_exp = 0.0;
  double max_freq_exp = 8.0;
  bool include_input = true;
};

// Output width: in_dim·2·num_frequencies (+ in_dim with include_input). 21 for in_dim 1, 63 for 3.
int64_t nerf_encoding_dim(const NerfEncodingOptions& options);

// The frequencies f_k as float32 values promoted to `dtype`: [num_frequencies].
torch::Tensor nerf_encoding_frequencies(const NerfEncodingOptions& options,
                                        torch::Dtype dtype = torch::kFloat64);

// x: [..., in_dim] (floating point; the computation runs in x's dtype) → [..., nerf_encoding_dim].
torch::Tensor nerf_encode(const torch::Tensor& x, const NerfEncodingOptions& options);

}  // namespace neraf::acoustic
