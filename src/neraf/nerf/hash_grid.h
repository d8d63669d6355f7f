#pragma once
// Multiresolution hash encoding as a differentiable LibTorch op (tiny-cuda-nn semantics; the exact
// formulas are in hash_grid_kernel.h) plus an nn::Module that owns the table.
//
// Devices: on CPU the op runs the custom kernels (hash_grid_kernel.h). On any other device it falls
// back to hash_grid_encode_reference (plain tensor ops, autograd), which is slow but correct; a
// CUDA build can route to its own kernel at the single dispatch point in hash_grid.cpp.
#include <torch/torch.h>

#include <cstdint>

#include "neraf/nerf/hash_grid_kernel.h"

namespace neraf::nerf {

// x:     [N, 3] contracted-cube coordinates in [0, 1], contiguous (float32; float64 also accepted
//        when the table is float64, for finite-difference tests)
// table: [layout.total_entries, F], same dtype and device as x
// returns [N, L·F] (features of level 0, then level 1, ...), same dtype as the table.
// Gradients: w.r.t. the table always (a fresh dense [total_entries, F] tensor per backward: let
// the optimizer zero grads with set_to_none so autograd moves it in instead of adding 48 MB);
// w.r.t. x only when x.requires_grad() (Nerfacto's camera optimizer moves the sample positions,
// so they need it; it costs about one more forward pass). Not twice differentiable.
// Throws c10::Error (TORCH_CHECK) on wrong dtype, shape, device or contiguity.
torch::Tensor hash_grid_encode(const torch::Tensor& x, const torch::Tensor& table,
                               const HashGridLayout& layout);

// The same function written with LibTorch tensor ops only (index_select + autograd). Slow (seconds
// at Nerfacto sizes); used by the tests as the reference and as the non-CPU fallback. Works on any
// device and for float32/float64.
torch::Tensor hash_grid_encode_reference(const torch::Tensor& x, const torch::Tensor& table,
                                         const HashGridLayout& layout);

// Owns the table as the registered parameter "table": [layout.total_entries, F] float32,
// initialised uniform in ±1e-4 from `seed` (tcnn's initialisation), independent of the global RNG.
class HashGridImpl : public torch::nn::Module {
 public:
  explicit HashGridImpl(HashGridConfig config = {}, uint64_t seed = 1337);

  // x: [N, 3] in [0, 1] → [N, L·F]
  torch::Tensor forward(torch::Tensor x);

  int output_dim() const { return layout_.output_dim(); }
  const HashGridLayout& layout() const { return layout_; }

  torch::Tensor table;  // [total_entries, F]

 private:
  HashGridLayout layout_;
};
TORCH_MODULE(HashGrid);

}  // namespace neraf::nerf
