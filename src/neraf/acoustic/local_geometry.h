#pragma once
// Geometry per query (issue 13 §5, ours): the paper's grid reaches NAcF as one pooled vector per
// room, the same for every pose, so within a room it can only act as a learned constant. These
// stateless ops give each (microphone, source) query features of the scene encoder's volume
// before pooling, read where that query's sound travels:
//   at the microphone, at the source, and the mean and maximum over `segment_points` points
//   evenly inside the segment between them (what lies on the direct path: a wall, a doorway)
// → [B, 4·L] for an [L, D, H, W] volume.
//
// Coordinates: the volume covers the radiance field's hash-grid input cube u ∈ [0,1]³ (the voxel
// grid's space, grid_sampler.h) with dims (D, H, W) = (x, y, z), as the grid's flat cell index.
// Positions in the dataset's metres reach it through the data's world transform (WorldToField:
// orientation, centring and scale of the image poses; the RIR positions must be in the cameras'
// frame, as `neraf synth` writes them) and the scene contraction. Sampling is trilinear between
// voxel centres ((i + 0.5)/n per axis of the volume's own frame), clamped to the border voxels;
// strided_map_coordinates moves a point of the grid into the frame of a map the grid was
// convolved into with stride 2.
#include <torch/types.h>

#include <array>
#include <cstdint>

namespace neraf::acoustic {

// Metres of the dataset frame → the radiance field's normalised frame: p' = A·p + b, row-major
// [A | b] (the data's world_transform with its scale folded in). Identity by default.
using WorldToField = std::array<double, 12>;
constexpr WorldToField kIdentityWorldToField = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

// p_m: [B, 3] metres → [B, 3] float32 hash-grid input u = (contract(A·p + b) + 2)/4 ∈ (0, 1)³.
torch::Tensor world_to_grid_input(const torch::Tensor& p_m, const WorldToField& world_to_field);

// Trilinear samples of volume [L, D, H, W] at u: [N, 3] → [N, L] (differentiable in the volume).
torch::Tensor sample_volume(const torch::Tensor& volume, const torch::Tensor& u);

// u of an S-cell grid → the same point in the frame of a map made from it by a stride-2
// convolution padded by half its (odd) kernel, whose voxel o is centred on grid cell 2o (S' =
// ⌈S/2⌉ voxels): u' = (u·S + 0.5)/(2·S'), so that sample_volume(map, u') reads voxel o at cell
// 2o's centre. [N, 3] → [N, 3].
torch::Tensor strided_map_coordinates(const torch::Tensor& u, int64_t grid_resolution,
                                      int64_t map_resolution);

// volume: [L, D, H, W]; mic_u, src_u: [B, 3] in the volume's frame;
// segment_points ≥ 1 → [B, 4·L] = [at mic, at source, mean and max over the segment's points
// t_k = (k + 0.5)/K, k = 0..K−1].
torch::Tensor local_geometry_features(const torch::Tensor& volume, const torch::Tensor& mic_u,
                                      const torch::Tensor& src_u, int64_t segment_points);

}  // namespace neraf::acoustic
