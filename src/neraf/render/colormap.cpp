#include "neraf/render/colormap.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

namespace neraf::render {

namespace {

// 3×5 glyphs, one row per 3 bits (MSB = left column).
struct Glyph {
  char c;
  unsigned char rows[5];
};
constexpr Glyph kFont[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
    {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}},
    {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}}, {'.', {0, 0, 0, 0, 2}}, {'-', {0, 0, 7, 0, 0}},
    {'+', {0, 2, 7, 2, 0}}, {'x', {0, 5, 2, 5, 0}}, {'y', {5, 5, 2, 2, 2}}, {'z', {0, 7, 2, 4, 7}},
    {'m', {0, 7, 7, 5, 5}}, {'d', {1, 1, 7, 5, 7}}, {'B', {6, 5, 6, 5, 6}}, {'l', {2, 2, 2, 2, 2}},
    {'o', {0, 7, 5, 5, 7}}, {'g', {7, 5, 7, 1, 6}}, {'(', {1, 2, 2, 2, 1}}, {')', {4, 2, 2, 2, 4}},
    {'s', {0, 7, 4, 1, 7}}, {'r', {0, 7, 4, 4, 4}}, {'c', {0, 7, 4, 4, 7}},
};

const Glyph* find_glyph(char c) {
  for (const Glyph& g : kFont) {
    if (g.c == c) return &g;
  }
  return nullptr;
}

}  // namespace

Canvas::Canvas(int width, int height, float r, float g, float b)
    : width_(width), height_(height), pixels_(torch::empty({height, width, 3}, torch::kFloat32)) {
  fill_rect(0, 0, width, height, r, g, b);
}

void Canvas::fill_rect(int x0, int y0, int x1, int y1, float r, float g, float b) {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0);
  x1 = std::min(x1, width_), y1 = std::min(y1, height_);
  if (x0 >= x1 || y0 >= y1) return;
  auto acc = pixels_.accessor<float, 3>();
  for (int y = y0; y < y1; ++y) {
    for (int x = x0; x < x1; ++x) {
      acc[y][x][0] = r, acc[y][x][1] = g, acc[y][x][2] = b;
    }
  }
}

void Canvas::paste(const torch::Tensor& img, int x, int y) {
  const int h = static_cast<int>(img.size(0)), w = static_cast<int>(img.size(1));
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  const int x1 = std::min(x + w, width_), y1 = std::min(y + h, height_);
  if (x0 >= x1 || y0 >= y1) return;
  using torch::indexing::Slice;
  pixels_.index_put_({Slice(y0, y1), Slice(x0, x1)},
                     img.index({Slice(y0 - y, y1 - y), Slice(x0 - x, x1 - x)}).to(torch::kFloat32));
}

void Canvas::text(const std::string& s, int x, int y, int scale, float r, float g, float b) {
  for (size_t i = 0; i < s.size(); ++i) {
    const Glyph* glyph = find_glyph(s[i]);
    if (glyph == nullptr) continue;
    const int gx = x + int(i) * 4 * scale;
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < 3; ++col) {
        if (glyph->rows[row] & (4 >> col)) {
          fill_rect(gx + col * scale, y + row * scale, gx + (col + 1) * scale,
                    y + (row + 1) * scale, r, g, b);
        }
      }
    }
  }
}

void Canvas::ring(double cx, double cy, double radius, double thickness, float r, float g,
                  float b) {
  const int x0 = int(std::floor(cx - radius - thickness)),
            x1 = int(std::ceil(cx + radius + thickness));
  const int y0 = int(std::floor(cy - radius - thickness)),
            y1 = int(std::ceil(cy + radius + thickness));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
      if (std::abs(d - radius) <= thickness / 2) fill_rect(x, y, x + 1, y + 1, r, g, b);
    }
  }
}

}  // namespace neraf::render
