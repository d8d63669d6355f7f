#pragma once
// Nerfacto's training losses (nerfstudio model_components/losses.py semantics).
#include <torch/types.h>

#include <vector>

namespace neraf::nerf {

// mean((pred − gt)²) over all elements.
torch::Tensor mean_squared_error(const torch::Tensor& pred, const torch::Tensor& gt);

// mip-NeRF 360 "outer" bound: for each target interval [t0_i, t0_{i+1}] the sum of the envelope
// weights y1 of the source intervals that overlap it (searchsorted on the envelope's edges).
// t0: [R, S0 + 1] target edges, t1: [R, S1 + 1] envelope edges, y1: [R, S1] → [R, S0].
torch::Tensor outer_weights(const torch::Tensor& t0, const torch::Tensor& t1,
                            const torch::Tensor& y1);

// Interlevel (proposal) loss: for each proposal level k,
//   mean( clip(w − outer(c, c_k, w_k), 0)² / (w + 1e-7) )
// with c, w the final (nerf) level's spacing edges and weights, detached (targets only), summed
// over the proposal levels. weights[k]: [R, S_k]; sdist[k]: [R, S_k + 1]; the last entry is the
// nerf level.
torch::Tensor interlevel_loss(const std::vector<torch::Tensor>& weights,
                              const std::vector<torch::Tensor>& sdist);

// mip-NeRF 360 distortion loss on one level, mean over rays:
//   Σ_ij w_i w_j |m_i − m_j| + (1/3) Σ_i w_i² (s_{i+1} − s_i),  m = spacing midpoints.
// Computed in O(S) with cumulative sums (midpoints are sorted), equal to the O(S²) definition.
torch::Tensor distortion_loss(const torch::Tensor& weights, const torch::Tensor& sdist);

}  // namespace neraf::nerf
