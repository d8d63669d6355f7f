#include "neraf/acoustic/schedule.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

namespace neraf::acoustic {
namespace {

TEST(Schedule, AudioWarmupAndDecay) {
  const auto s = audio_schedule();
  EXPECT_DOUBLE_EQ(scheduled_lr(s, 0), 1e-8);
  EXPECT_NEAR(scheduled_lr(s, 1000), 1e-8 + (1e-4 - 1e-8) * std::sqrt(0.5), 1e-18);
  EXPECT_NEAR(scheduled_lr(s, 1), 1e-8 + (1e-4 - 1e-8) * std::sin(M_PI / 4000.0), 1e-18);
  EXPECT_NEAR(scheduled_lr(s, 1999), 1e-4, 1e-10);
  EXPECT_NEAR(scheduled_lr(s, 2000), 1e-4, 1e-18);
  // Log-linear: halfway through the decay the lr is the geometric mean, 1e-6.
  EXPECT_NEAR(scheduled_lr(s, 2000 + 500000), 1e-6, 1e-15);
  // At the end of the reference run (step 400k): 10^(−4·0.602 − 8·0.398) ≈ 2.56e-6.
  EXPECT_NEAR(scheduled_lr(s, 400000), std::pow(10.0, -4.0 * 0.602 - 8.0 * 0.398), 1e-12);
  EXPECT_NEAR(scheduled_lr(s, 400000), 2.56e-6, 0.01e-6);
  EXPECT_NEAR(scheduled_lr(s, 1002000), 1e-8, 1e-20);
  EXPECT_NEAR(scheduled_lr(s, 5000000), 1e-8, 1e-20);  // flat afterwards
}

TEST(Schedule, LinearRampAndNoWarmup) {
  ExponentialDecaySchedule s;
  s.lr_init = 1e-2;
  s.lr_final = 1e-4;
  s.warmup_steps = 0;
  s.max_steps = 200000;
  EXPECT_DOUBLE_EQ(scheduled_lr(s, 0), 1e-2);
  EXPECT_NEAR(scheduled_lr(s, 100000), 1e-3, 1e-15);
  EXPECT_NEAR(scheduled_lr(s, 30000), std::pow(10.0, -2.0 - 2.0 * 0.15), 1e-15);  // ≈ 5.0e-3
  s.warmup_steps = 100;
  s.ramp = WarmupRamp::kLinear;
  EXPECT_NEAR(scheduled_lr(s, 25), 1e-8 + (1e-2 - 1e-8) * 0.25, 1e-15);
}

TEST(Schedule, AdamSettingsAndLrSetter) {
  auto p = torch::zeros({3}, torch::requires_grad());
  auto opt = make_adam({p});
  const auto& o = static_cast<const torch::optim::AdamOptions&>(opt->param_groups()[0].options());
  EXPECT_DOUBLE_EQ(o.lr(), 1e-4);
  EXPECT_DOUBLE_EQ(o.eps(), 1e-15);
  EXPECT_DOUBLE_EQ(std::get<0>(o.betas()), 0.9);
  EXPECT_DOUBLE_EQ(std::get<1>(o.betas()), 0.999);
  EXPECT_DOUBLE_EQ(o.weight_decay(), 0.0);
  set_adam_lr(*opt, scheduled_lr(audio_schedule(), 0));
  EXPECT_DOUBLE_EQ(
      static_cast<const torch::optim::AdamOptions&>(opt->param_groups()[0].options()).lr(), 1e-8);
  // One Adam step moves each parameter by ≈ lr (bias-corrected first step).
  p.mutable_grad() = torch::ones({3});
  opt->step();
  EXPECT_NEAR(p[0].item<double>(), -1e-8, 1e-12);
}

}  // namespace
}  // namespace neraf::acoustic
