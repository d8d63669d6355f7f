#pragma once
// Colour maps and a few pixel-drawing helpers for plots written as PNG (heat maps with tick
// marks, numbers and a colour bar) without a plotting library.
#include <torch/types.h>

#include <cstdint>
#include <string>

namespace neraf::render {

// An RGB canvas [H, W, 3] float in [0, 1] with simple drawing operations (all clip at the edges).
class Canvas {
 public:
  Canvas(int width, int height, float r = 1, float g = 1, float b = 1);
  int width() const { return width_; }
  int height() const { return height_; }
  torch::Tensor& pixels() { return pixels_; }  // [H, W, 3]

  void fill_rect(int x0, int y0, int x1, int y1, float r, float g, float b);  // [x0, x1) × [y0, y1)
  // Pastes img [h, w, 3] with its top-left corner at (x, y).
  void paste(const torch::Tensor& img, int x, int y);
  // Text in a 3×5 pixel font scaled by `scale`: digits, '.', '-', '+', ' ', and the letters
  // x y z m d B l o g (others draw as blanks). (x, y) is the top-left corner.
  void text(const std::string& s, int x, int y, int scale, float r, float g, float b);
  static int text_width(const std::string& s, int scale) { return int(s.size()) * 4 * scale; }
  void ring(double cx, double cy, double radius, double thickness, float r, float g, float b);

 private:
  int width_, height_;
  torch::Tensor pixels_;
};

}  // namespace neraf::render
