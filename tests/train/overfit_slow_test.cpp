// A tiny overfit: a few dozen steps on a synthetic 8×8, 2-view scene must reduce the loss.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "../infer/synthetic_scene.h"
#include "neraf/train/trainer.h"

using namespace neraf::train;
using namespace neraf::infer;

TEST(Overfit, FortyStepsReduceTheLoss) {
  const auto images = fixtures::make_image_set(2, 8);
  for (auto precision : {neraf::nerf::Precision::fp32, neraf::nerf::Precision::bf16}) {
    TrainConfig cfg = fixtures::tiny_train_config();
    cfg.model.precision = precision;
    cfg.rays_per_batch = 128;
    cfg.steps = 60;
    cfg.fields.max_steps = cfg.proposal_networks.max_steps = 60;
    auto t = make_trainer(cfg, &images, torch::kCPU);
    double first = 0, last = 0;
    for (int i = 0; i < 60; ++i) {
      const StepResult r = t->step();
      if (i < 5) first += r.losses.at("rgb_loss") / 5;
      if (i >= 55) last += r.losses.at("rgb_loss") / 5;
    }
    std::printf("%s: rgb loss %.4f → %.4f\n", neraf::nerf::to_string(precision).c_str(), first,
                last);
    EXPECT_LT(last, 0.5 * first);
  }
}
