#include "neraf/acoustic/losses.h"

#include <torch/torch.h>

namespace neraf::acoustic {

std::optional<AudioCriterion> parse_audio_criterion(const std::string& name) {
  if (name == "sc_slmse") return AudioCriterion::sc_slmse;
  if (name == "sc_sll1") return AudioCriterion::sc_sll1;
  if (name == "mse") return AudioCriterion::mse;
  return std::nullopt;
}

namespace {
// t.sc given: the criterion's log-magnitude term and the weighted sum (p, g: float32 log-mags).
AudioLossTerms with_log_magnitude_term(AudioLossTerms t, const torch::Tensor& p,
                                       const torch::Tensor& g, const AudioLossOptions& options) {
  t.sl =
      options.criterion == AudioCriterion::sc_sll1 ? torch::l1_loss(p, g) : torch::mse_loss(p, g);
  const double sc_weight = options.criterion == AudioCriterion::mse ? 0.0 : options.sc_weight;
  t.sc_loss = t.sc * (options.loss_factor * sc_weight);
  t.mag_loss = t.sl * (options.loss_factor * options.mag_weight);
  t.total = t.sc_loss + t.mag_loss;
  return t;
}
}  // namespace

AudioLossTerms spectral_loss(const torch::Tensor& pred, const torch::Tensor& gt,
                             const AudioLossOptions& options) {
  TORCH_CHECK(pred.sizes() == gt.sizes(), "spectral_loss: pred ", pred.sizes(), " vs gt ",
              gt.sizes());
  const auto p = pred.to(torch::kFloat32);
  const auto g = gt.to(torch::kFloat32);
  const auto x = torch::exp(p) - 1e-3;
  const auto y = torch::exp(g) - 1e-3;
  AudioLossTerms t;
  t.sc = torch::norm(y - x) / torch::norm(y);  // Frobenius over the whole batch
  return with_log_magnitude_term(t, p, g, options);
}

AudioLossTerms spectral_loss_sharded(const torch::Tensor& pred, const torch::Tensor& gt,
                                     const std::function<void(torch::Tensor&)>& sum_over_ranks,
                                     int world_size, const AudioLossOptions& options) {
  TORCH_CHECK(pred.sizes() == gt.sizes(), "spectral_loss_sharded: pred ", pred.sizes(), " vs gt ",
              gt.sizes());
  const auto p = pred.to(torch::kFloat32);
  const auto g = gt.to(torch::kFloat32);
  const auto x = torch::exp(p) - 1e-3;
  const auto y = torch::exp(g) - 1e-3;
  const torch::Tensor num = (y - x).pow(2).sum();  // [] this rank's ‖Y − X‖²
  torch::Tensor sums = torch::stack({num.detach(), y.pow(2).sum().detach()});  // [2]
  sum_over_ranks(sums);
  const torch::Tensor n_all = sums[0].clamp_min(1e-30), d_all = sums[1].clamp_min(1e-30);
  const torch::Tensor sc_all = torch::sqrt(n_all / d_all);  // [] the global SC
  // d(√(N/D))/dnum = 1 / (2·√N·√D): this rank's share of the gradient, × world_size because the
  // trainer averages the ranks' gradients.
  const torch::Tensor surrogate = num * (world_size / (2.0 * torch::sqrt(n_all * d_all)));
  AudioLossTerms t;
  t.sc = surrogate + (sc_all - surrogate).detach();  // value: the global SC
  return with_log_magnitude_term(t, p, g, options);
}

torch::Tensor energy_decay_loss(const torch::Tensor& pred, const torch::Tensor& gt, double eps,
                                double floor_db) {
  TORCH_CHECK(pred.dim() == 4 && pred.sizes() == gt.sizes(),
              "energy_decay_loss: expected equal [B, C, F, T] shapes, got ", pred.sizes(), " and ",
              gt.sizes());
  auto decay_log10 = [eps](const torch::Tensor& log_mag) {
    const auto m = torch::clamp_min(torch::exp(log_mag.to(torch::kFloat32)) - 1e-3, 0.0);
    const auto e = (m * m).sum(2);                                           // [B, C, T]
    const auto d = torch::flip(torch::cumsum(torch::flip(e, {2}), 2), {2});  // Σ_{τ≥t}
    return torch::log10(d + eps);
  };
  torch::Tensor p = decay_log10(pred), g = decay_log10(gt);  // [B, C, T]
  if (floor_db > 0) {
    const torch::Tensor floor = g.narrow(2, 0, 1) - floor_db / 10.0;  // [B, C, 1]
    p = torch::maximum(p, floor);
    g = torch::maximum(g, floor);
  }
  return torch::abs(p - g).mean();
}

}  // namespace neraf::acoustic
