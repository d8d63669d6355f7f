#include "neraf/acoustic/schedule.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "neraf/util/error.h"

namespace neraf::acoustic {

double scheduled_lr(const ExponentialDecaySchedule& s, int64_t step) {
  require(s.lr_init > 0 && s.lr_final > 0, "lr schedule: lr_init and lr_final must be positive");
  if (step < s.warmup_steps) {
    const double x =
        std::clamp(static_cast<double>(step) / static_cast<double>(s.warmup_steps), 0.0, 1.0);
    const double ramp = s.ramp == WarmupRamp::kSine ? std::sin(0.5 * M_PI * x) : x;
    return s.lr_pre_warmup + (s.lr_init - s.lr_pre_warmup) * ramp;
  }
  const int64_t span = s.max_steps - s.warmup_steps;
  const double t =
      span <= 0 ? 1.0
                : std::clamp(static_cast<double>(step - s.warmup_steps) / static_cast<double>(span),
                             0.0, 1.0);
  return std::exp(std::log(s.lr_init) * (1.0 - t) + std::log(s.lr_final) * t);
}

std::unique_ptr<torch::optim::Adam> make_adam(std::vector<torch::Tensor> params,
                                              const AdamSettings& settings) {
  torch::optim::AdamOptions o(settings.lr);
  o.eps(settings.eps).betas({settings.beta1, settings.beta2}).weight_decay(0.0);
  return std::make_unique<torch::optim::Adam>(std::move(params), o);
}

void set_adam_lr(torch::optim::Adam& optimizer, double lr) {
  for (auto& group : optimizer.param_groups()) {
    static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
  }
}

}  // namespace neraf::acoustic
