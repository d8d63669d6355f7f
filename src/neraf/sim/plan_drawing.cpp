#include "neraf/sim/plan_drawing.h"

#include <stb/stb_easy_font.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "neraf/geometry/pose.h"
#include "neraf/io/png.h"
#include "neraf/sim/scene_json.h"

namespace neraf::sim {

namespace {

struct P2 {
  double x, y;  // pixels
};

// The drawing primitives; every one clips at the picture's edges. A pixel is painted when its
// centre lies inside the shape.
class Raster {
 public:
  Raster(int w, int h, Rgb8 bg) : w_(w), h_(h), px_(size_t(w) * h * 3) {
    for (size_t i = 0; i < px_.size(); i += 3) std::copy(bg.begin(), bg.end(), px_.begin() + i);
  }
  std::vector<uint8_t> take() { return std::move(px_); }

  void set(int c, int r, Rgb8 col) {
    if (c < 0 || r < 0 || c >= w_ || r >= h_) return;
    std::copy(col.begin(), col.end(), px_.begin() + (size_t(r) * w_ + c) * 3);
  }
  // Pixels with centres in [x0, x1) × [y0, y1).
  void rect(double x0, double y0, double x1, double y1, Rgb8 col) {
    for (int r = first(y0); r + 0.5 < y1; ++r)
      for (int c = first(x0); c + 0.5 < x1; ++c) set(c, r, col);
  }
  // A convex polygon (vertices in order, either sense).
  void polygon(const std::vector<P2>& v, Rgb8 col) {
    double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
    for (const P2& p : v) {
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y),
      y1 = std::max(y1, p.y);
    }
    for (int r = first(y0); r + 0.5 <= y1; ++r) {
      for (int c = first(x0); c + 0.5 <= x1; ++c) {
        const P2 q{c + 0.5, r + 0.5};
        bool pos = false, neg = false;
        for (size_t i = 0; i < v.size(); ++i) {
          const P2 a = v[i], b = v[(i + 1) % v.size()];
          const double cr = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
          pos |= cr > 1e-9, neg |= cr < -1e-9;
        }
        if (!(pos && neg)) set(c, r, col);
      }
    }
  }
  // A segment of the given width (pixels), round caps.
  void line(P2 a, P2 b, double width, Rgb8 col) {
    const double h = 0.5 * width;
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    for (int r = first(std::min(a.y, b.y) - h); r + 0.5 <= std::max(a.y, b.y) + h; ++r) {
      for (int c = first(std::min(a.x, b.x) - h); c + 0.5 <= std::max(a.x, b.x) + h; ++c) {
        const double qx = c + 0.5 - a.x, qy = r + 0.5 - a.y;
        const double t = len2 > 0 ? std::clamp((qx * dx + qy * dy) / len2, 0.0, 1.0) : 0.0;
        const double ex = qx - t * dx, ey = qy - t * dy;
        if (ex * ex + ey * ey <= h * h) set(c, r, col);
      }
    }
  }
  void polyline_closed(const std::vector<P2>& v, double width, Rgb8 col) {
    for (size_t i = 0; i < v.size(); ++i) line(v[i], v[(i + 1) % v.size()], width, col);
  }
  void disc(P2 c, double radius, Rgb8 col) {
    for (int r = first(c.y - radius); r + 0.5 <= c.y + radius; ++r)
      for (int x = first(c.x - radius); x + 0.5 <= c.x + radius; ++x) {
        const double dx = x + 0.5 - c.x, dy = r + 0.5 - c.y;
        if (dx * dx + dy * dy <= radius * radius) set(x, r, col);
      }
  }
  // ASCII text with its top-left corner at (x, y), stb_easy_font's glyphs scaled by `scale`.
  void text(const std::string& s, double x, double y, int scale, Rgb8 col) {
    std::vector<char> buf(s.begin(), s.end());
    buf.push_back('\0');
    std::vector<float> verts(buf.size() * 270 + 64);  // ≤ ~270 floats of quads per glyph
    unsigned char rgba[4] = {col[0], col[1], col[2], 255};
    const int quads = stb_easy_font_print(0, 0, buf.data(), rgba, verts.data(),
                                          static_cast<int>(verts.size() * sizeof(float)));
    for (int q = 0; q < quads; ++q) {
      const float* v = verts.data() + q * 16;  // 4 vertices × (x, y, z, rgba)
      const double qx0 = std::min(v[0], v[8]), qx1 = std::max(v[0], v[8]);
      const double qy0 = std::min(v[1], v[9]), qy1 = std::max(v[1], v[9]);
      rect(x + qx0 * scale, y + qy0 * scale, x + qx1 * scale, y + qy1 * scale, col);
    }
  }

 private:
  static int first(double lo) { return static_cast<int>(std::ceil(lo - 0.5)); }
  int w_, h_;
  std::vector<uint8_t> px_;
};

int text_width(const std::string& s, int scale) {
  std::vector<char> buf(s.begin(), s.end());
  buf.push_back('\0');
  return stb_easy_font_width(buf.data()) * scale;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

enum class BoxKind { furniture, wall, overhead };

BoxKind classify(const Scene& s, const Box& b) {
  const double bottom = b.center.y - 0.5 * b.size.y, top = b.center.y + 0.5 * b.size.y;
  if (bottom <= kPlanFullHeightTolM && top >= s.size.y - kPlanFullHeightTolM) return BoxKind::wall;
  if (bottom > kPlanOverheadBottomM) return BoxKind::overhead;
  return BoxKind::furniture;
}

constexpr Rgb8 kBlack{0, 0, 0};
constexpr Rgb8 kGrey{110, 110, 110};
constexpr Rgb8 kFurnitureEdge{130, 95, 55};

// The marker of each kind, shared by the plan and its legend.
void draw_microphone(Raster& r, P2 p, double radius) { r.disc(p, radius, kPlanMicrophone); }

void draw_source(Raster& r, P2 p, double yaw_deg, bool directional, double radius) {
  if (directional) {
    const geometry::Vec3 f = geometry::heading_forward(yaw_deg);
    const double len = 4.0 * radius;
    const P2 tip{p.x + f.x * len, p.y + f.z * len};
    r.line(p, tip, 2.5, kPlanSource);
    const double bx = -f.x, bz = -f.z;  // the arrow head: two strokes back from the tip
    for (double side : {-1.0, 1.0}) {
      const double c = std::cos(0.5 * side), s = std::sin(0.5 * side);
      const P2 end{tip.x + (c * bx - s * bz) * radius, tip.y + (s * bx + c * bz) * radius};
      r.line(tip, end, 2.5, kPlanSource);
    }
  }
  r.disc(p, radius + 1.5, kBlack);
  r.disc(p, radius, kPlanSource);
}

void draw_camera(Raster& r, P2 p, const geometry::Vec3& forward, Rgb8 col) {
  const double h = std::hypot(forward.x, forward.z);
  if (h > 1e-9) r.line(p, {p.x + 9 * forward.x / h, p.y + 9 * forward.z / h}, 1.5, col);
  r.rect(p.x - 2.5, p.y - 2.5, p.x + 2.5, p.y + 2.5, col);
}

}  // namespace

Rgb8 PlanImage::pixel(int c, int r) const {
  const size_t i = (size_t(r) * width + c) * 3;
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

PlanImage draw_plan(const Scene& scene, const SynthPlan& plan) {
  PlanImage img;
  const double longest = std::max(scene.size.x, scene.size.z);
  img.px_per_m = std::clamp(std::round(640.0 / longest), 8.0, 160.0);
  constexpr int kLeft = 70, kTop = 70, kBottom = 60, kLegend = 300, kRight = 20;
  img.left_px = kLeft;
  img.top_px = kTop;
  const int room_w = static_cast<int>(std::ceil(scene.size.x * img.px_per_m));
  const int room_h = static_cast<int>(std::ceil(scene.size.z * img.px_per_m));
  img.width = kLeft + room_w + 20 + kLegend + kRight;
  img.height = kTop + std::max(room_h, 330) + kBottom;
  Raster r(img.width, img.height, kPlanBackground);
  const auto at = [&](double x, double z) { return P2{img.column(x), img.row(z)}; };

  // Floor, boxes (furniture, then walls, then overhead outlines), the room's outline.
  r.rect(img.column(0), img.row(0), img.column(scene.size.x), img.row(scene.size.z), kPlanFloor);
  const auto corners = [&](const Box& b) {
    const geometry::YawBox yb = furniture_box(b);
    std::vector<P2> v;
    for (auto [sx, sz] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
      const geometry::Vec3 w =
          yb.center + geometry::rotate_y({sx * yb.half.x, 0, sz * yb.half.z}, yb.yaw_rad);
      v.push_back(at(w.x, w.z));
    }
    return v;
  };
  bool any_wall = false, any_overhead = false, any_furniture = false;
  for (const Box& b : scene.furniture) {
    if (classify(scene, b) != BoxKind::furniture) continue;
    any_furniture = true;
    const auto v = corners(b);
    r.polygon(v, kPlanFurniture);
    r.polyline_closed(v, 1.0, kFurnitureEdge);
  }
  for (const Box& b : scene.furniture) {
    if (classify(scene, b) != BoxKind::wall) continue;
    any_wall = true;
    r.polygon(corners(b), kPlanWall);
  }
  for (const Box& b : scene.furniture) {
    if (classify(scene, b) != BoxKind::overhead) continue;
    any_overhead = true;
    r.polyline_closed(corners(b), 1.0, kPlanOverhead);
  }
  r.polyline_closed(
      {at(0, 0), at(scene.size.x, 0), at(scene.size.x, scene.size.z), at(0, scene.size.z)}, 3.0,
      kBlack);

  // Cameras, microphones, sources (on top, labelled S0, S1, ...).
  for (const auto& c : plan.train_cameras)
    draw_camera(r, at(c.pose.position.x, c.pose.position.z), c.pose.forward(), kPlanTrainCamera);
  for (const auto& c : plan.eval_cameras)
    draw_camera(r, at(c.pose.position.x, c.pose.position.z), c.pose.forward(), kPlanEvalCamera);
  const double mic_r = plan.microphones.size() > 2000 ? 1.0 : img.px_per_m >= 60 ? 3.0 : 2.0;
  for (const auto& m : plan.microphones) draw_microphone(r, at(m.x, m.z), mic_r);
  for (size_t i = 0; i < scene.sources.size(); ++i) {
    const Source& s = scene.sources[i];
    const P2 p = at(s.position.x, s.position.z);
    draw_source(r, p, s.yaw_deg, s.directivity != "omni", 5.0);
    r.text("S" + std::to_string(i), p.x + 8, p.y + 4, 2, kBlack);
  }

  // Axes: ticks every 1, 2 or 5 m, numbers, names.
  const double step = longest <= 8 ? 1 : longest <= 20 ? 2 : 5;
  for (double x = 0; x <= scene.size.x + 1e-9; x += step) {
    const double c = img.column(x), y = img.row(scene.size.z);
    r.line({c, y + 2}, {c, y + 9}, 1.5, kBlack);
    const std::string l = fmt("%g", x);
    r.text(l, c - text_width(l, 2) / 2.0, y + 13, 2, kBlack);
  }
  for (double z = 0; z <= scene.size.z + 1e-9; z += step) {
    const double y = img.row(z), c = img.column(0);
    r.line({c - 9, y}, {c - 2, y}, 1.5, kBlack);
    const std::string l = fmt("%g", z);
    r.text(l, c - 14 - text_width(l, 2), y - 6, 2, kBlack);
  }
  r.text("x (m)", img.column(scene.size.x) - text_width("x (m)", 2), img.row(scene.size.z) + 36, 2,
         kBlack);
  r.text("z (m)", 8, img.row(0) - 24, 2, kBlack);

  // Title: the scene and what the layout makes of it.
  const int headings = plan.binaural ? static_cast<int>(plan.headings_deg.size()) : 1;
  r.text(scene.name + "  " + fmt("%g", scene.size.x) + " x " + fmt("%g", scene.size.y) + " x " +
             fmt("%g", scene.size.z) + " m (x, height, z), top view",
         kLeft, 12, 2, kBlack);
  std::string counts = plan.layout + " layout: " + std::to_string(plan.jobs.size()) +
                       " RIRs = " + std::to_string(plan.microphones.size()) + " mics";
  if (plan.binaural) counts += " x " + std::to_string(headings) + " headings";
  counts += " x " + std::to_string(scene.sources.size()) + " sources";
  r.text(counts, kLeft, 36, 2, kGrey);

  // Legend.
  const double lx = kLeft + room_w + 30;
  double ly = kTop + 4;
  const auto entry = [&](const std::string& label) {
    r.text(label, lx + 34, ly - 6, 2, kBlack);
    ly += 30;
  };
  draw_microphone(r, {lx + 12, ly}, 3.0);
  entry(plan.binaural ? "microphone (" + std::to_string(headings) + " headings)"
                      : "microphone (omni)");
  draw_source(r, {lx + 12, ly}, 0, false, 5.0);
  entry("omni source");
  draw_source(r, {lx + 12, ly + 6}, 0, true, 5.0);  // faces -z: up in the picture
  entry("");
  ly -= 30;
  r.text("directional source,", lx + 34, ly - 6, 2, kBlack);
  r.text("arrow = facing", lx + 34, ly + 12, 2, kBlack);
  ly += 42;
  if (any_furniture) {
    r.rect(lx, ly - 8, lx + 24, ly + 8, kPlanFurniture);
    entry("furniture");
  }
  if (any_wall) {
    r.rect(lx, ly - 8, lx + 24, ly + 8, kPlanWall);
    entry("wall (full height)");
  }
  if (any_overhead) {
    r.polyline_closed({{lx, ly - 8}, {lx + 24, ly - 8}, {lx + 24, ly + 8}, {lx, ly + 8}}, 1.0,
                      kPlanOverhead);
    entry("above head (lintel)");
  }
  if (!plan.train_cameras.empty()) {
    draw_camera(r, {lx + 8, ly}, {1, 0, 0}, kPlanTrainCamera);
    entry("train camera + view");
  }
  if (!plan.eval_cameras.empty()) {
    draw_camera(r, {lx + 8, ly}, {1, 0, 0}, kPlanEvalCamera);
    entry("eval camera + view");
  }
  img.rgb = r.take();
  return img;
}

void write_plan_png(const std::string& path, const PlanImage& image) {
  io::write_png(path, image.width, image.height, 3, image.rgb.data());
}

}  // namespace neraf::sim
