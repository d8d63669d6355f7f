#include "neraf/nerf/volume_rendering.h"

#include <torch/torch.h>

namespace neraf::nerf {

torch::Tensor compute_weights(const torch::Tensor& densities, const torch::Tensor& deltas) {
  const torch::Tensor dd = densities * deltas;  // [R, S]
  const torch::Tensor alphas = 1.0 - torch::exp(-dd);
  // Exclusive cumulative sum: transmittance before each sample.
  const torch::Tensor excl =
      torch::cat({torch::zeros({dd.size(0), 1}, dd.options()), torch::cumsum(dd.slice(1, 0, -1), 1)},
                 1);
  return torch::nan_to_num(alphas * torch::exp(-excl));
}

torch::Tensor composite_rgb(const torch::Tensor& weights, const torch::Tensor& rgb) {
  const torch::Tensor comp = (weights.unsqueeze(-1) * rgb).sum(1);  // [R, 3]
  const torch::Tensor background = rgb.select(1, rgb.size(1) - 1);  // [R, 3]
  return comp + background * (1.0 - weights.sum(1, /*keepdim=*/true));
}

torch::Tensor accumulation(const torch::Tensor& weights) { return weights.sum(1); }

torch::Tensor expected_depth(const torch::Tensor& weights, const torch::Tensor& tdist) {
  const torch::Tensor mids = (tdist.slice(1, 0, -1) + tdist.slice(1, 1)) * 0.5;  // [R, S]
  const torch::Tensor depth = (weights * mids).sum(1) / (weights.sum(1) + 1e-10);
  return torch::clamp(depth, mids.min(), mids.max());  // tensor bounds: no host sync
}

torch::Tensor median_depth(const torch::Tensor& weights, const torch::Tensor& tdist) {
  torch::NoGradGuard no_grad;
  const torch::Tensor mids = (tdist.slice(1, 0, -1) + tdist.slice(1, 1)) * 0.5;  // [R, S]
  const torch::Tensor cum = torch::cumsum(weights, 1).contiguous();
  const torch::Tensor half = torch::full({weights.size(0), 1}, 0.5, weights.options());
  const torch::Tensor idx =
      torch::searchsorted(cum, half, /*out_int32=*/false, /*right=*/false).clamp(0, mids.size(1) - 1);
  return mids.gather(1, idx).squeeze(1);
}

}  // namespace neraf::nerf
