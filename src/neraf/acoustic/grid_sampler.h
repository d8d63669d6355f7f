#pragma once
// The 7×S³ voxel grid that summarises the radiance field for the acoustic branch
// (neraf-reference.md §1.4): channels 0-2 RGB, 3 alpha, 4-6 the cell-centre coordinates.
//
// * Cells: centres (i + 0.5)/S per axis in the radiance field's hash-grid input space u ∈ [0,1]³
//   (with nerfstudio's L∞ contraction that is contracted space [-2,2]³, i.e. the whole unbounded
//   scene). Flat cell index n = (i·S + j)·S + k for centre (x_i, y_j, z_k): x-major, z fastest,
//   exactly the reference's meshgrid('ij') + flatten.
// * Update: `update(field)` writes `cells_per_update` consecutive cells (round robin over the flat
//   index, wrapping at S³) with RGB = mean over the view directions of the field's rgb and
//   alpha = clip(1 − exp(−δ·σ̄), 0, 1), σ̄ the mean density, δ = 0.01. The grid is first detached,
//   then the fresh values are written in place: only the cells written by the latest update carry
//   an autograd path to the radiance field; all other cells are constants (the reference's
//   `grid = grid.detach(); grid[...] = values`). In eval mode `update` does nothing.
// * View directions: by default 18 unit directions spread evenly over the sphere (Fibonacci
//   sphere, below). ViewDirections::kReference reproduces the reference's 18 degenerate vectors
//   (6 zero vectors, 6 distinct non-unit vectors each twice) for parity runs only.
// * State: the grid and the round-robin pointer are registered buffers ("grid", "pointer"), so
//   they travel with the module's checkpoints (the reference saves `audio_model.grid`).
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>

namespace neraf::acoustic {

// The radiance field seen by the grid sampler. u: [N, 3] hash-grid input in [0,1]³, dirs: [N, 3]
// view directions → (density [N], rgb [N, 3]). The caller binds everything else (appearance
// embedding: the reference uses train image 0's; spatial distortion: none — u is the hash input).
using FieldQueryFn = std::function<std::pair<torch::Tensor, torch::Tensor>(
    const torch::Tensor& u, const torch::Tensor& dirs)>;

enum class ViewDirections {
  kSpread,     // `num_directions` unit vectors on a Fibonacci sphere (default; our improvement)
  kReference,  // the published code's 18 vectors (cosφ·sinθ, cosφ·sinθ, sinθ), for parity
};
ViewDirections parse_view_directions(const std::string& name);  // "spread" | "reference"
std::string to_string(ViewDirections directions);

struct GridSamplerOptions {
  int64_t resolution = 32;          // S; preset cpu 32, paper 128
  int64_t cells_per_update = 4096;  // cells written per update (paper: 4096 = rays per batch)
  ViewDirections view_directions = ViewDirections::kSpread;
  int64_t num_directions = 18;  // kSpread only (kReference is always 18)
  double delta = 0.01;          // alpha = 1 − exp(−delta·density)
};

// Fibonacci sphere: d_i = (r cos φ_i, r sin φ_i, z_i) with z_i = 1 − (2i + 1)/n, r = √(1 − z_i²),
// φ_i = i·π(3 − √5) (golden angle). Equal-area spacing, no duplicates, no zero vectors. [n, 3].
torch::Tensor fibonacci_sphere_directions(int64_t n);
// The reference's 18 vectors: φ ∈ {π/3, 0, −π} (outer loop), θ = k·π/3, k = 0..5 (inner loop),
// d = (cosφ·sinθ, cosφ·sinθ, sinθ), unnormalised. [18, 3]. The order is irrelevant (averaged).
torch::Tensor reference_view_directions();

// Cell centres (i + 0.5)/S per axis: [S].
torch::Tensor grid_cell_centres_1d(int64_t resolution);
// Centres of the flat cells [first, first + count) (wrapping at S³): [count, 3].
torch::Tensor grid_cell_centres(int64_t resolution, int64_t first, int64_t count);

class GridSamplerImpl : public torch::nn::Module {
 public:
  explicit GridSamplerImpl(GridSamplerOptions options = {});

  // Writes the next `cells_per_update` cells from `field` (with autograd) and advances the pointer.
  // No-op in eval mode. Returns the flat indices written ([n] int64; empty in eval mode).
  torch::Tensor update(const FieldQueryFn& field);

  // Recomputes every cell without autograd, `chunk` cells per field call (e.g. after loading a
  // radiance field trained elsewhere). Works in any mode; does not move the pointer.
  void refresh_all(const FieldQueryFn& field, int64_t chunk = 32768);

  // Resets to the initial state: zeros in channels 0-3, coordinates in 4-6, pointer 0.
  void reset();

  // The current grid [7, S, S, S] (cells of the latest update carry autograd history).
  const torch::Tensor& grid() const { return grid_; }
  int64_t pointer() const;                                         // next flat cell to write
  const torch::Tensor& directions() const { return directions_; }  // [D, 3]
  const GridSamplerOptions& options() const { return options_; }

  // Computes the 4 written channels for `u` ([n, 3] cell centres): [4, n] = (r, g, b, alpha).
  torch::Tensor query_cells(const FieldQueryFn& field, const torch::Tensor& u) const;

 private:
  GridSamplerOptions options_;
  torch::Tensor grid_;        // buffer "grid": [7, S, S, S] float32
  torch::Tensor pointer_;     // buffer "pointer": [] int64
  torch::Tensor directions_;  // [D, 3] float32 (not saved: derived from the options)
};
TORCH_MODULE(GridSampler);

}  // namespace neraf::acoustic
