#include "neraf/nerf/contraction.h"

#include <torch/torch.h>

namespace neraf::nerf {

torch::Tensor scene_contract(const torch::Tensor& x) {
  // ‖x‖∞ per point; where it is ≤ 1 the point is unchanged. The scale factor is computed on a
  // clamped norm so the untaken branch never divides by zero (no NaN in the gradient).
  const torch::Tensor mag = x.abs().amax(-1, /*keepdim=*/true);  // [..., 1]
  const torch::Tensor safe = mag.clamp_min(1.0);
  const torch::Tensor scale = (2.0 - 1.0 / safe) / safe;  // == 1 where mag ≤ 1
  return x * scale;
}

GridInput grid_input_from_u(const torch::Tensor& u) {
  const torch::Tensor selector = ((u > 0.0) & (u < 1.0)).all(-1);  // [...]
  // where() rather than a product: a NaN position must not leak into the grid lookup.
  return {torch::where(selector.unsqueeze(-1), u, torch::zeros({}, u.options())), selector};
}

GridInput contract_to_grid_input(const torch::Tensor& x) {
  return grid_input_from_u((scene_contract(x) + 2.0) * 0.25);
}

}  // namespace neraf::nerf
