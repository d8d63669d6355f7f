// Slow: a few dozen joint steps on the tiny SoundSpaces fixture reduce the audio loss.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <numeric>

#include "../infer/audio_test_util.h"
#include "neraf/train/audio_branch.h"
#include "neraf/train/trainer.h"

namespace neraf::train {
namespace {

using infer::TrainConfig;
namespace fixtures = infer::fixtures;

TEST(AudioBranchSlow, JointTrainingReducesTheAudioLoss) {
  torch::manual_seed(0);
  const std::string dir = fixtures::make_temp_dir("slow");
  const data::RirSet rirs = fixtures::tiny_rir_set(dir);
  const data::ImageSet images = fixtures::make_image_set();
  TrainConfig c = fixtures::tiny_joint_config();
  c.steps = 60;
  auto trainer = make_trainer(c, &images, torch::kCPU, &rirs);
  std::vector<double> mag;
  for (int i = 0; i < 60; ++i) mag.push_back(trainer->step().losses.at("audio_mag_loss"));
  const double first = std::accumulate(mag.begin(), mag.begin() + 5, 0.0) / 5;
  const double last = std::accumulate(mag.end() - 5, mag.end(), 0.0) / 5;
  EXPECT_LT(last, 0.5 * first) << "first " << first << " last " << last;
}

}  // namespace
}  // namespace neraf::train
