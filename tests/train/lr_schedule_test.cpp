#include "neraf/train/lr_schedule.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace neraf::train;
using namespace neraf::infer;

TEST(LrSchedule, NerfactoFieldsDecay) {
  ScheduleConfig s;  // 1e-2 → 1e-4 over 200k steps
  EXPECT_DOUBLE_EQ(learning_rate(s, 0), 1e-2);
  EXPECT_NEAR(learning_rate(s, 100000), 1e-3, 1e-15);
  EXPECT_NEAR(learning_rate(s, 200000), 1e-4, 1e-16);
  EXPECT_NEAR(learning_rate(s, 500000), 1e-4, 1e-16);  // flat after max_steps
  // nerfstudio's note: at 30k steps ≈ 5.0e-3.
  EXPECT_NEAR(learning_rate(s, 30000), 1e-2 * std::pow(10.0, -0.3), 1e-12);
  EXPECT_NEAR(learning_rate(s, 30000), 5.0119e-3, 1e-6);
}

TEST(LrSchedule, CameraOptDecay) {
  ScheduleConfig s{1e-3, 1e-4, 5000};
  EXPECT_DOUBLE_EQ(learning_rate(s, 0), 1e-3);
  EXPECT_NEAR(learning_rate(s, 2500), std::sqrt(1e-7), 1e-15);
  EXPECT_NEAR(learning_rate(s, 5000), 1e-4, 1e-16);
  EXPECT_NEAR(learning_rate(s, 10000), 1e-4, 1e-16);
}

TEST(LrSchedule, WarmupRamps) {
  ScheduleConfig s{1e-4, 1e-8, 1002000, 2000};
  EXPECT_DOUBLE_EQ(learning_rate(s, 0), 1e-8);
  EXPECT_NEAR(learning_rate(s, 1000), 1e-8 + (1e-4 - 1e-8) * 0.5, 1e-18);
  EXPECT_NEAR(learning_rate(s, 2000), 1e-4, 1e-16);
  s.warmup_ramp = "sine";
  EXPECT_NEAR(learning_rate(s, 1000), 1e-8 + (1e-4 - 1e-8) * std::sin(M_PI / 4), 1e-18);
  // After the warm-up: log-linear over the remaining 1,000,000 steps.
  EXPECT_NEAR(learning_rate(s, 502000), std::sqrt(1e-4 * 1e-8), 1e-15);
}

TEST(LrSchedule, WarmupFromALaterStart) {
  ScheduleConfig s{2e-3, 1e-4, 3000, 100, 1e-8, "linear", 1e-15, 1000};
  EXPECT_DOUBLE_EQ(learning_rate(s, 0), 1e-8);  // before the branch starts
  EXPECT_DOUBLE_EQ(learning_rate(s, 1000), 1e-8);
  EXPECT_NEAR(learning_rate(s, 1050), 1e-8 + (2e-3 - 1e-8) * 0.5, 1e-18);
  EXPECT_NEAR(learning_rate(s, 1100), 2e-3, 1e-16);
  // Then log-linear over the remaining 1900 steps, flat afterwards.
  EXPECT_NEAR(learning_rate(s, 2050), std::sqrt(2e-3 * 1e-4), 1e-15);
  EXPECT_NEAR(learning_rate(s, 3000), 1e-4, 1e-16);
  EXPECT_NEAR(learning_rate(s, 5000), 1e-4, 1e-16);
  // No warm-up at all (a short run's is capped to 0): the pre-warm-up LR up to the start, never
  // 0 / 0 (a NaN LR reached the radiance field through the audio group).
  s.warmup_steps = 0;
  EXPECT_DOUBLE_EQ(learning_rate(s, 999), 1e-8);
  EXPECT_NEAR(learning_rate(s, 1000), 2e-3, 1e-16);
  // A run shortened on --resume to end inside its warm-up: the ramp, then lr_final, never NaN.
  s.warmup_steps = 100;
  s.max_steps = 1050;
  EXPECT_NEAR(learning_rate(s, 1025), 1e-8 + (2e-3 - 1e-8) * 0.25, 1e-18);
  EXPECT_DOUBLE_EQ(learning_rate(s, 1100), 1e-4);
  s.max_steps = 1100;
  EXPECT_DOUBLE_EQ(learning_rate(s, 1100), 1e-4);
}

TEST(LrSchedule, CpuPresetDecaysOverTheRun) {
  const TrainConfig c = train_preset("cpu");
  EXPECT_DOUBLE_EQ(learning_rate(c.fields, 0), c.fields.lr);
  EXPECT_NEAR(learning_rate(c.fields, c.steps), c.fields.lr_final, 1e-15);
  const TrainConfig p = train_preset("paper");
  EXPECT_EQ(p.fields.max_steps, 200000);
  EXPECT_DOUBLE_EQ(p.fields.lr_final, 1e-4);
  EXPECT_DOUBLE_EQ(p.camera_opt.lr, 1e-3);
  EXPECT_DOUBLE_EQ(p.fields.eps, 1e-15);
}
