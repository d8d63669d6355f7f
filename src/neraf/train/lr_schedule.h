#pragma once
// Learning rate as a pure function of the step (nerfstudio ExponentialDecayScheduler semantics;
// the optimizer step with index `step` uses lr(step)).
#include <cstdint>

#include "neraf/infer/train_config.h"

namespace neraf::train {

//   step < warmup: lr_pre_warmup + (lr − lr_pre_warmup)·r, r = step/warmup (linear) or
//                  sin(π/2 · step/warmup) (sine)
//   else:          exp(ln lr·(1 − s) + ln lr_final·s), s = clip((step − warmup)/(max − warmup), 0,
//   1)
double learning_rate(const infer::ScheduleConfig& schedule, int64_t step);

}  // namespace neraf::train
