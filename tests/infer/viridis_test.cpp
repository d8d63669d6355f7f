#include <gtest/gtest.h>
#include <torch/torch.h>

#include "neraf/infer/image_output.h"

namespace neraf::infer {
namespace {

TEST(Viridis, EndpointsAndMiddleMatchMatplotlib) {
  const torch::Tensor c = viridis(torch::tensor({0.0, 0.5, 1.0}));
  ASSERT_EQ(c.sizes(), (std::vector<int64_t>{3, 3}));
  EXPECT_NEAR(c[0][0].item<float>(), 0.267004f, 1e-6);
  EXPECT_NEAR(c[0][1].item<float>(), 0.004874f, 1e-6);
  EXPECT_NEAR(c[0][2].item<float>(), 0.329415f, 1e-6);
  EXPECT_NEAR(c[1][0].item<float>(), 0.127568f, 1e-6);
  EXPECT_NEAR(c[1][1].item<float>(), 0.566949f, 1e-6);
  EXPECT_NEAR(c[2][0].item<float>(), 0.993248f, 1e-6);
  EXPECT_NEAR(c[2][1].item<float>(), 0.906157f, 1e-6);
  EXPECT_NEAR(c[2][2].item<float>(), 0.143936f, 1e-6);
}

TEST(Viridis, ClampsAndKeepsShape) {
  const torch::Tensor c = viridis(torch::tensor({-3.0, 7.0}).view({1, 2}));
  ASSERT_EQ(c.sizes(), (std::vector<int64_t>{1, 2, 3}));
  EXPECT_TRUE(torch::allclose(c[0][0], viridis(torch::tensor({0.0}))[0]));
  EXPECT_TRUE(torch::allclose(c[0][1], viridis(torch::tensor({1.0}))[0]));
}

TEST(Viridis, GreenRisesMonotonically) {
  const torch::Tensor c = viridis(torch::linspace(0, 1, 101));
  const torch::Tensor g = c.select(1, 1);
  EXPECT_TRUE((g.slice(0, 1) - g.slice(0, 0, -1) >= 0).all().item<bool>());
}

}  // namespace
}  // namespace neraf::infer
