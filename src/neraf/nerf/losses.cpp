#include "neraf/nerf/losses.h"

#include <torch/torch.h>

namespace neraf::nerf {

torch::Tensor mean_squared_error(const torch::Tensor& pred, const torch::Tensor& gt) {
  return (pred - gt).pow(2).mean();
}

torch::Tensor outer_weights(const torch::Tensor& t0, const torch::Tensor& t1,
                            const torch::Tensor& y1) {
  const int64_t S1 = y1.size(1);
  const torch::Tensor cy1 =
      torch::cat({torch::zeros({y1.size(0), 1}, y1.options()), torch::cumsum(y1, 1)}, 1);
  const torch::Tensor t0_starts = t0.slice(1, 0, -1).contiguous();
  const torch::Tensor t0_ends = t0.slice(1, 1).contiguous();
  const torch::Tensor t1_starts = t1.slice(1, 0, -1).contiguous();
  const torch::Tensor t1_ends = t1.slice(1, 1).contiguous();
  const torch::Tensor idx_lo =
      (torch::searchsorted(t1_starts, t0_starts, false, /*right=*/true) - 1).clamp(0, S1 - 1);
  const torch::Tensor idx_hi =
      torch::searchsorted(t1_ends, t0_ends, false, /*right=*/true).clamp(0, S1 - 1);
  const torch::Tensor cy1_lo = cy1.slice(1, 0, -1).gather(1, idx_lo);
  const torch::Tensor cy1_hi = cy1.slice(1, 1).gather(1, idx_hi);
  return cy1_hi - cy1_lo;
}

torch::Tensor interlevel_loss(const std::vector<torch::Tensor>& weights,
                              const std::vector<torch::Tensor>& sdist) {
  TORCH_CHECK(weights.size() == sdist.size() && weights.size() >= 2,
              "interlevel_loss: need matching lists with at least two levels");
  const torch::Tensor c = sdist.back().detach();
  const torch::Tensor w = weights.back().detach();
  torch::Tensor loss = torch::zeros({}, w.options());
  for (size_t k = 0; k + 1 < weights.size(); ++k) {
    const torch::Tensor w_outer = outer_weights(c, sdist[k], weights[k]);
    loss = loss + (torch::clamp_min(w - w_outer, 0.0).pow(2) / (w + 1e-7)).mean();
  }
  return loss;
}

torch::Tensor distortion_loss(const torch::Tensor& weights, const torch::Tensor& sdist) {
  const torch::Tensor& w = weights;                                          // [R, S]
  const torch::Tensor m = (sdist.slice(1, 1) + sdist.slice(1, 0, -1)) * 0.5;  // [R, S] sorted
  // Σ_ij w_i w_j |m_i − m_j| = 2 Σ_i w_i (m_i W_<i − (wm)_<i), exclusive prefix sums.
  const torch::Tensor wm = w * m;
  const torch::Tensor w_excl = torch::cumsum(w, 1) - w;
  const torch::Tensor wm_excl = torch::cumsum(wm, 1) - wm;
  const torch::Tensor inter = 2.0 * (w * (m * w_excl - wm_excl)).sum(1);
  const torch::Tensor intra = (w.pow(2) * (sdist.slice(1, 1) - sdist.slice(1, 0, -1))).sum(1) / 3.0;
  return (inter + intra).mean();
}

}  // namespace neraf::nerf
