#include <gtest/gtest.h>
#include <torch/torch.h>

#include "neraf/render/colormap.h"

namespace neraf::render {
namespace {

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
