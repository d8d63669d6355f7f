#pragma once
// Volume rendering along contiguous samples (nerfstudio RaySamples.get_weights and renderers).
#include <torch/types.h>

namespace neraf::nerf {

// α_i = 1 − exp(−σ_i δ_i); T_i = exp(−Σ_{j<i} σ_j δ_j); w_i = α_i T_i; NaN → 0.
// densities, deltas: [R, S] → weights [R, S].
torch::Tensor compute_weights(const torch::Tensor& densities, const torch::Tensor& deltas);

// Σ w_i c_i + c_bg (1 − Σ w_i) with background "last_sample": c_bg = rgb of the last sample.
// weights [R, S], rgb [R, S, 3] → [R, 3]. (Callers clamp to [0, 1] for evaluation.)
torch::Tensor composite_rgb(const torch::Tensor& weights, const torch::Tensor& rgb);

// Σ w_i: [R].
torch::Tensor accumulation(const torch::Tensor& weights);

// Σ w_i m_i / (Σ w_i + 1e-10), clipped to [min m, max m]; m = bin midpoints from tdist [R, S+1].
torch::Tensor expected_depth(const torch::Tensor& weights, const torch::Tensor& tdist);

// Midpoint of the first sample whose cumulative weight reaches 0.5 (searchsorted left; the last
// sample if none does). No gradient. [R].
torch::Tensor median_depth(const torch::Tensor& weights, const torch::Tensor& tdist);

}  // namespace neraf::nerf
