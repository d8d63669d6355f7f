#pragma once
// Learning rate as a pure function of the step (nerfstudio ExponentialDecayScheduler semantics;
// the optimizer step with index `step` uses lr(step)).
#include <cstdint>

#include "neraf/infer/train_config.h"

namespace neraf::train {

//   step < start + warmup: lr_pre_warmup + (lr − lr_pre_warmup)·r, x = max(0, step − start)/warmup,
//                          r = x (linear) or sin(π/2 · x) (sine)
//   else:                  exp(ln lr·(1 − s) + ln lr_final·s),
//                          s = clip((step − start − warmup)/(max − start − warmup), 0, 1)
// (start = warmup_start, warmup = warmup_steps, max = max_steps)
double learning_rate(const infer::ScheduleConfig& schedule, int64_t step);

}  // namespace neraf::train
