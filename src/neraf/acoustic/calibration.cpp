#include "neraf/acoustic/calibration.h"

#include <torch/torch.h>

#include <algorithm>

namespace neraf::acoustic {

namespace {
constexpr double kFloor = 1e-3;  // the log-magnitude offset, neraf-reference.md §4.1

torch::Tensor magnitude(const torch::Tensor& log_stft) {  // in float64: energies are summed
  return log_stft_to_magnitude(log_stft.to(torch::kFloat64));
}
}  // namespace

torch::Tensor log_stft_to_magnitude(const torch::Tensor& log_stft) {
  return torch::clamp(torch::exp(log_stft) - kFloor, 0.0, 1e4);
}

torch::Tensor bin_energy(const torch::Tensor& log_stft) {
  TORCH_CHECK(log_stft.dim() >= 3, "bin_energy: expected [..., C, F, T], got ", log_stft.sizes());
  const int64_t C = log_stft.size(-3), F = log_stft.size(-2), T = log_stft.size(-1);
  return magnitude(log_stft).pow(2).reshape({-1, C, F, T}).sum(0);  // [C, F, T]
}

torch::Tensor calibration_gain(const torch::Tensor& gt_energy, const torch::Tensor& pred_energy) {
  TORCH_CHECK(gt_energy.dim() == 3 && gt_energy.sizes() == pred_energy.sizes(),
              "calibration_gain: expected two [C, F, T] energies, got ", gt_energy.sizes(), " and ",
              pred_energy.sizes());
  const torch::Tensor gt = gt_energy.to(torch::kFloat64), pred = pred_energy.to(torch::kFloat64);
  const torch::Tensor both = (gt > 0) & (pred > 0);
  const torch::Tensor ratio = torch::where(both, gt / pred.clamp_min(1e-300), torch::ones_like(gt));
  return ratio.sqrt().clamp(1.0 / kMaxCalibrationGain, kMaxCalibrationGain).to(torch::kFloat32);
}

torch::Tensor with_early_balance(const torch::Tensor& gain, const torch::Tensor& delta_db,
                                 int64_t hop, int64_t split_sample) {
  TORCH_CHECK(gain.dim() == 3 && delta_db.dim() == 1 && delta_db.size(0) == gain.size(0),
              "with_early_balance: expected gain [C, F, T] and delta [C], got ", gain.sizes(),
              " and ", delta_db.sizes());
  TORCH_CHECK(hop > 0, "with_early_balance: hop must be positive");
  const int64_t early = std::min(gain.size(2), (split_sample + hop - 1) / hop);  // t·hop < split
  torch::Tensor factor = torch::ones({gain.size(0), 1, gain.size(2)}, torch::kFloat64);
  factor.slice(2, 0, early)
      .copy_(torch::pow(10.0, delta_db.to(torch::kFloat64) / 20.0).view({-1, 1, 1}));
  return (gain.to(torch::kFloat64) * factor)
      .clamp(1.0 / kMaxCalibrationGain, kMaxCalibrationGain)
      .to(torch::kFloat32);
}

torch::Tensor apply_calibration(const torch::Tensor& log_stft, const torch::Tensor& gain) {
  TORCH_CHECK(log_stft.dim() >= 3 && gain.dim() == 3 &&
                  gain.sizes() == log_stft.sizes().slice(log_stft.dim() - 3),
              "apply_calibration: gain ", gain.sizes(), " does not match [..., C, F, T] ",
              log_stft.sizes());
  const torch::Tensor g = gain.to(log_stft.device(), torch::kFloat64);  // [C, F, T]
  return torch::log(magnitude(log_stft) * g + kFloor).to(log_stft.scalar_type());
}

}  // namespace neraf::acoustic
