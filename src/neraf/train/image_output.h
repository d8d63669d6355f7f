#pragma once
// Writing rendered images: float [0,1] tensors → 8-bit PNG files (atomic).
#include <torch/types.h>

#include <string>

namespace neraf::train {

// [H, W, C] float in [0, 1] (clamped) → [H, W, C] uint8, rounding to nearest.
torch::Tensor to_uint8(const torch::Tensor& image);

// Writes an [H, W, 3] or [H, W, 1] image (uint8, or float in [0, 1]) as PNG, atomically.
void write_png(const std::string& path, const torch::Tensor& image);

}  // namespace neraf::train
