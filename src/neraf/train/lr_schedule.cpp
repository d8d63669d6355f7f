#include "neraf/train/lr_schedule.h"

#include <algorithm>
#include <cmath>

namespace neraf::train {

double learning_rate(const infer::ScheduleConfig& s, int64_t step) {
  const int64_t warm_end = s.warmup_start + s.warmup_steps;
  if (step < s.warmup_start) return s.lr_pre_warmup;  // also when there is no warm-up (0 / 0)
  if (step < warm_end) {
    const double x =
        static_cast<double>(step - s.warmup_start) / static_cast<double>(s.warmup_steps);
    const double r = s.warmup_ramp == "sine" ? std::sin(0.5 * M_PI * x) : x;
    return s.lr_pre_warmup + (s.lr - s.lr_pre_warmup) * r;
  }
  // A run shortened on --resume may end inside its warm-up: then it never gets here.
  if (s.max_steps <= warm_end) return s.lr_final;
  const double t = std::clamp(
      static_cast<double>(step - warm_end) / static_cast<double>(s.max_steps - warm_end), 0.0, 1.0);
  return std::exp(std::log(s.lr) * (1.0 - t) + std::log(s.lr_final) * t);
}

}  // namespace neraf::train
