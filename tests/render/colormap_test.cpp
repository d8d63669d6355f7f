#include "neraf/render/colormap.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

namespace neraf::render {
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

TEST(Canvas, DrawsRectsTextAndClips) {
  Canvas c(20, 10);
  EXPECT_FLOAT_EQ(c.pixels()[5][5][0].item<float>(), 1.0f);
  c.fill_rect(-5, -5, 3, 2, 0, 0, 0);  // clipped at the top-left corner
  EXPECT_FLOAT_EQ(c.pixels()[1][2][1].item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(c.pixels()[2][2][1].item<float>(), 1.0f);
  Canvas t(8, 6);
  t.text("1", 0, 0, 1, 0, 0, 0);  // glyph rows 010 110 010 010 111
  EXPECT_FLOAT_EQ(t.pixels()[0][1][0].item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(t.pixels()[0][0][0].item<float>(), 1.0f);
  EXPECT_FLOAT_EQ(t.pixels()[4][2][0].item<float>(), 0.0f);
  EXPECT_EQ(Canvas::text_width("12", 2), 16);
  t.text("9999999", 5, 4, 3, 0, 0, 0);  // mostly off-canvas: must not crash
}

}  // namespace
}  // namespace neraf::render
