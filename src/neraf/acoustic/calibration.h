#pragma once
// Per-frame energy calibration of predicted log-magnitude STFTs (ours, not in the reference).
//
// NAcF is trained with an MSE on log(|STFT| + 1e-3). On the diffuse tail, where |STFT| is
// Rayleigh-like noise around a decaying envelope, that predicts the mean of the log, which sits
// below the log of the energy by up to ~2.5 dB, and by less where the envelope nears the 1e-3
// floor. The late tail thus comes out relatively too loud and the decay too slow: on the demo
// room every T60 was ~2 % long. One gain per (channel, bin, frame), fitted on the TRAINING RIRs
// after training, restores the mean energy of each bin and frame (the bias depends on both: high
// bins reach the floor sooner):
//   E[c, f, t] = M[c, f, t]²,  M = clip(exp(log_stft) − 1e-3, 0, 1e4)       (bin_energy)
//   g[c, f, t] = sqrt(Σ_train E_gt / Σ_train E_pred), 1 where either sum is 0, clamped to
//                [1/kMaxGain, kMaxGain]                                      (calibration_gain)
//   log_stft'  = log(M · g + 1e-3)                                          (apply_calibration)
// The metrics are untouched; the prediction only changes by a per-frame factor.
//
// Early/late balance (with_early_balance), fitted after the gains above: rendered through
// Griffin-Lim, as evaluation renders, the calibrated training predictions still came out with a
// C50 ~0.2 dB low on the demo room (the direct sound and first reflections are smoothed over the
// RIRs they arrive in at different frames, and Griffin-Lim spreads what remains). One more factor
// per channel, 10^(Δ_c/20) with Δ_c the mean (C50_gt − C50_rendered) over training RIRs, on the
// frames whose centre lies before C50's split.
#include <torch/types.h>

namespace neraf::acoustic {

constexpr double kMaxCalibrationGain = 10.0;

// NAcF's output decoding, mag = clip(exp(log_stft) − 1e-3, 0, 1e4) (neraf-reference.md §4.1).
// Any shape, the input's dtype.
torch::Tensor log_stft_to_magnitude(const torch::Tensor& log_stft);

// log_stft: [..., C, F, T] → [C, F, T] float64 energies summed over all leading dims.
torch::Tensor bin_energy(const torch::Tensor& log_stft);

// gt_energy, pred_energy: [C, F, T] sums of bin_energy over the same RIRs → [C, F, T] float32
// gains.
torch::Tensor calibration_gain(const torch::Tensor& gt_energy, const torch::Tensor& pred_energy);

// gain: [C, F, T]; delta_db: [C] → gain with frames t (centre t·hop) < split_sample of channel c
// multiplied by 10^(delta_db[c]/20), clamped to [1/kMaxCalibrationGain, kMaxCalibrationGain].
torch::Tensor with_early_balance(const torch::Tensor& gain, const torch::Tensor& delta_db,
                                 int64_t hop, int64_t split_sample);

// log_stft: [..., C, F, T], gain: [C, F, T] → calibrated log_stft (same shape, dtype, device).
torch::Tensor apply_calibration(const torch::Tensor& log_stft, const torch::Tensor& gain);

}  // namespace neraf::acoustic
