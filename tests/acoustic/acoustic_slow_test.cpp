// Paper-size checks that take seconds on 2 cores.
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "neraf/acoustic/acoustic_model.h"
#include "neraf/acoustic/resnet3d.h"

namespace neraf::acoustic {
namespace {

TEST(ResNet3dSlow, PaperAt128MatchesAvgPool8) {
  torch::manual_seed(0);
  ResNet3d net(resnet3d_paper_options());
  torch::NoGradGuard g;
  const auto x = torch::rand({1, 7, 128, 128, 128});
  const auto fm = net->feature_map(x);
  // 128 → 64 (conv1) → 32 (max pool) → 32 → 16 → 8.
  ASSERT_EQ(fm.sizes(), (std::vector<int64_t>{1, 1024, 8, 8, 8}));
  // The reference's AvgPool3d(kernel 8, stride 1) equals our adaptive (global) average here.
  const auto ref = torch::avg_pool3d(fm, 8, 1).flatten(1);
  const auto y = torch::adaptive_avg_pool3d(fm, {1, 1, 1}).flatten(1);
  EXPECT_TRUE(torch::allclose(ref, y, 1e-5, 1e-6));
  EXPECT_EQ(y.sizes(), (std::vector<int64_t>{1, 1024}));
}

TEST(AcousticModelSlow, PaperRenderStftAt128) {
  torch::manual_seed(1);
  AcousticModel m(acoustic_preset("paper", 2, 257, 78));
  GridSampler sampler(m->options().grid);
  const auto stft = m->render_stft(sampler->grid(), torch::rand({3}, torch::kFloat64),
                                   torch::rand({3}, torch::kFloat64),
                                   torch::tensor({0.5, 0.5, 1.0}, torch::kFloat64));
  EXPECT_EQ(stft.sizes(), (std::vector<int64_t>{2, 257, 78}));
  EXPECT_LT(stft.abs().max().item<float>(), 10.0f);
}

}  // namespace
}  // namespace neraf::acoustic
