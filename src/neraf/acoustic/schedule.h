#pragma once
// Optimiser and learning-rate schedule helpers (neraf-reference.md §2.3).
//
// The schedule is nerfstudio's ExponentialDecayScheduler as a pure function of the step:
//   step < warmup:  lr = lr_pre_warmup + (lr_init − lr_pre_warmup)·ramp(step/warmup),
//                   ramp = sin(π/2·x) (kSine, nerfstudio's "cosine" option) or x (kLinear)
//   otherwise:      s = clip((step − warmup)/(max_steps − warmup), 0, 1)
//                   lr = exp(ln lr_init·(1 − s) + ln lr_final·s)
// The audio group ("audio_fields") uses Adam lr 1e-4, eps 1e-15, betas (0.9, 0.999), no weight
// decay, warm-up 2000 steps from 1e-8, then 1e-4 → 1e-8 over max_steps 1,002,000. `step` counts
// scheduler steps, i.e. training steps since the optimiser was created (the reference's audio
// optimiser steps from training step 0 because it also holds the radiance-field parameters).
#include <torch/optim/adam.h>
#include <torch/types.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace neraf::acoustic {

enum class WarmupRamp { kSine, kLinear };

struct ExponentialDecaySchedule {
  double lr_init = 1e-4;
  double lr_final = 1e-8;
  double lr_pre_warmup = 1e-8;
  int64_t warmup_steps = 2000;
  int64_t max_steps = 1002000;
  WarmupRamp ramp = WarmupRamp::kSine;
};

// The audio group's schedule (the defaults above).
inline ExponentialDecaySchedule audio_schedule() { return {}; }

double scheduled_lr(const ExponentialDecaySchedule& schedule, int64_t step);

struct AdamSettings {
  double lr = 1e-4;
  double eps = 1e-15;
  double beta1 = 0.9;
  double beta2 = 0.999;
};

// Adam over `params` with the audio group's settings (lr is then driven by scheduled_lr).
std::unique_ptr<torch::optim::Adam> make_adam(std::vector<torch::Tensor> params,
                                              const AdamSettings& settings = {});

// Sets the learning rate of every parameter group of an Adam optimiser.
void set_adam_lr(torch::optim::Adam& optimizer, double lr);

}  // namespace neraf::acoustic
