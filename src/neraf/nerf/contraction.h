#pragma once
// nerfstudio SceneContraction(order=inf) and the map into the hash grid's input cube.
//   contract(x) = x                               if ‖x‖∞ ≤ 1
//               = (2 − 1/‖x‖∞) · x / ‖x‖∞          otherwise      (so contract(R³) = (−2, 2)³)
//   u = (contract(x) + 2) / 4 ∈ (0, 1)³
// Samples whose u falls outside the open cube (only possible for non-finite or ±∞ positions) are
// moved to the origin of the cube and get zero density (nerfstudio's `selector`).
#include <torch/types.h>

namespace neraf::nerf {

// x: [..., 3] → [..., 3] contracted into (−2, 2)³. Differentiable.
torch::Tensor scene_contract(const torch::Tensor& x);

struct GridInput {
  torch::Tensor u;         // [..., 3] hash-grid input, zeroed where !inside
  torch::Tensor selector;  // [...] bool: u was strictly inside (0, 1)³
};

// Contraction followed by (x + 2)/4 and the selector.
GridInput contract_to_grid_input(const torch::Tensor& x);

// For the query interface: u given directly (already in hash-grid input space).
GridInput grid_input_from_u(const torch::Tensor& u);

}  // namespace neraf::nerf
