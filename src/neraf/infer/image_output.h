#pragma once
// Writing rendered images: float [0,1] tensors → 8-bit PNG files (atomic), and the one colour
// map every plot uses (loudness maps, depth, log-STFT comparisons).
#include <torch/types.h>

#include <string>

namespace neraf::infer {

// [H, W, C] float in [0, 1] (clamped) → [H, W, C] uint8, rounding to nearest.
torch::Tensor to_uint8(const torch::Tensor& image);

// Viridis-like perceptually ordered map (dark purple → blue → green → yellow), linear between 9
// stops taken from matplotlib's viridis at t = 0, 1/8, ..., 1. t [...] (clamped to [0, 1]) →
// [..., 3] float in [0, 1].
torch::Tensor viridis(const torch::Tensor& t);

// Writes an [H, W, 3] or [H, W, 1] image (uint8, or float in [0, 1]) as PNG, atomically.
void write_png(const std::string& path, const torch::Tensor& image);

}  // namespace neraf::infer
