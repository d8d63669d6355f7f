#pragma once
// Audio losses (neraf-reference.md §2.2).
//
// "SC+SLMSE" (the reference's criterion) on a batch of predicted / ground-truth log-magnitude
// frames [B, C, F] (log(|STFT| + 1e-3)):
//   X = exp(pred) − 1e-3,  Y = exp(gt) − 1e-3     (no clipping, as the reference)
//   SC = ‖Y − X‖_F / ‖Y‖_F over the WHOLE batch tensor (one ratio, not a per-sample mean)
//   SL = mean((gt − pred)²)
//   audio_sc_loss = loss_factor·sc_weight·SC = 1e-3·0.1·SC,  audio_mag_loss = 1e-3·1.0·SL
// The paper's loss study also trains with "SC+SLL1" (SL = mean|gt − pred|, the reference's other
// criterion string) and "MSE" (SL alone: audio_sc_loss is 0, SC is still reported).
//
// Energy-decay loss (optional, the paper's "++" variant; the published code only carries it as a
// comment): on whole RIRs [B, C, F, T] (all T frames of each RIR, in order),
//   M = clamp(exp(log_mag) − 1e-3, 0)           magnitudes
//   E_t = Σ_f M[f, t]²                           frame energy
//   D_t = Σ_{τ ≥ t} E_τ                          backward cumulative energy (Schroeder curve)
//   decay = mean over (B, C, T) of |log10(D_t^pred + eps) − log10(D_t^gt + eps)|
// eps (1e-12) keeps an all-zero tail finite. audio_decay_loss = loss_factor·decay_weight·decay.
// With floor_db > 0 (ours; training uses 60 dB) both curves are clamped at floor_db below the
// ground truth's total energy D_0: the last frames' few-ULP energies otherwise dominate the log
// differences, while T60 (down to −35 dB), EDT and C50 only look at the top of the curve.
#include <torch/types.h>

#include <functional>
#include <optional>
#include <string>

namespace neraf::acoustic {

enum class AudioCriterion { sc_slmse, sc_sll1, mse };

// "sc_slmse" | "sc_sll1" | "mse" (the config's audio.loss, --audio-loss); nullopt otherwise.
std::optional<AudioCriterion> parse_audio_criterion(const std::string& name);

struct AudioLossOptions {
  AudioCriterion criterion = AudioCriterion::sc_slmse;
  double loss_factor = 1e-3;
  double sc_weight = 0.1;
  double mag_weight = 1.0;
  double decay_weight = 0.0;  // energy-decay term weight (0 = off, the reference)
  double decay_eps = 1e-12;
  double decay_floor_db = 60.0;
};

struct AudioLossTerms {
  torch::Tensor sc;        // [] raw spectral convergence ‖Y − X‖_F / ‖Y‖_F
  torch::Tensor sl;        // [] raw log-magnitude error (mean squared; mean absolute for sc_sll1)
  torch::Tensor sc_loss;   // [] audio_sc_loss = loss_factor·sc_weight·sc
  torch::Tensor mag_loss;  // [] audio_mag_loss = loss_factor·mag_weight·sl
  torch::Tensor total;     // [] sc_loss + mag_loss (+ decay_loss when added by the caller)
};

// pred, gt: [B, C, F] (any equal shape) log-magnitudes.
AudioLossTerms spectral_loss(const torch::Tensor& pred, const torch::Tensor& gt,
                             const AudioLossOptions& options = {});

// The same objective when the batch is split over `world_size` data-parallel ranks of equal
// shares (train/distributed.h), each calling this on its own rows: `sum_over_ranks` sums a small
// tensor in place over the ranks. The spectral convergence is a ratio of norms over the whole
// batch, not a mean, so its two sums of squares are summed over the ranks; the returned sc's
// value is the global SC on every rank and its gradient is world_size × this rank's share of the
// global SC's gradient, so the mean of the ranks' gradients is the gradient of the global SC
// (the trainer averages gradients). sl is this rank's mean (equal shares: the mean of the ranks'
// means is the global mean).
AudioLossTerms spectral_loss_sharded(const torch::Tensor& pred, const torch::Tensor& gt,
                                     const std::function<void(torch::Tensor&)>& sum_over_ranks,
                                     int world_size, const AudioLossOptions& options = {});

// pred, gt: [B, C, F, T] log-magnitudes of whole RIRs → [] raw energy-decay L1 (unweighted).
torch::Tensor energy_decay_loss(const torch::Tensor& pred, const torch::Tensor& gt,
                                double eps = 1e-12, double floor_db = 0.0);

}  // namespace neraf::acoustic
