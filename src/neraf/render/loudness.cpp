#include "neraf/render/loudness.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "neraf/infer/audio_run.h"
#include "neraf/infer/image_output.h"
#include "neraf/io/atomic_file.h"
#include "neraf/render/colormap.h"
#include "neraf/util/error.h"
#include "neraf/util/progress.h"

namespace neraf::render {

torch::Tensor FloorGrid::positions() const {
  torch::Tensor out = torch::empty({size(), 3}, torch::kFloat64);
  auto a = out.accessor<double, 2>();
  int64_t i = 0;
  for (double zv : z) {
    for (double xv : x) {
      a[i][0] = xv, a[i][1] = height, a[i][2] = zv;
      ++i;
    }
  }
  return out;
}

namespace {

std::vector<double> axis_points(double lo, double hi, double spacing) {
  std::vector<double> v;
  const int64_t n = static_cast<int64_t>(std::floor((hi - lo) / spacing + 1e-9)) + 1;
  for (int64_t i = 0; i < std::max<int64_t>(n, 1); ++i) v.push_back(lo + double(i) * spacing);
  return v;
}

}  // namespace

FloorGrid make_floor_grid(const data::Aabb& aabb, const FloorGridOptions& options) {
  require(options.spacing_m > 0 && std::isfinite(options.spacing_m),
          "--spacing: must be a positive number of metres (e.g. 0.1)");
  require(options.margin_m >= 0 && options.margin_m < 1.0,
          "loudness grid margin must be in [0, 1) m so the grid stays inside the audio aabb");
  // NeRAF's aabb is the train mic range ± 1 m; the reference grid is that range ± margin.
  const double pad = 1.0 - options.margin_m;
  const double x0 = aabb.min.x + pad, x1 = aabb.max.x - pad;
  const double z0 = aabb.min.z + pad, z1 = aabb.max.z - pad;
  FloorGrid g;
  g.height = std::isnan(options.height_m) ? 0.5 * (aabb.min.y + aabb.max.y) : options.height_m;
  require(std::isfinite(g.height) && g.height > aabb.min.y && g.height < aabb.max.y,
          "--height: " + std::to_string(g.height) +
              " m is outside the run's audio bounding box (y " + std::to_string(aabb.min.y) +
              " .. " + std::to_string(aabb.max.y) +
              "); predictions there are meaningless; choose a height inside it");
  double spacing = options.spacing_m;
  const double w = std::max(x1 - x0, 0.0), d = std::max(z1 - z0, 0.0);
  // Coarser when too many points: (w/s + 1)(d/s + 1) ≤ max_points.
  while ((std::floor(w / spacing + 1e-9) + 1) * (std::floor(d / spacing + 1e-9) + 1) >
         double(std::max<int64_t>(options.max_points, 1))) {
    spacing *= 1.25;
  }
  g.spacing = spacing;
  g.x = axis_points(x0, x1, spacing);
  g.z = axis_points(z0, z1, spacing);
  return g;
}

torch::Tensor spectrogram_rms(const torch::Tensor& magnitude) {
  TORCH_CHECK(magnitude.dim() >= 2 && magnitude.size(-2) >= 2, "spectrogram_rms: [..., F, T]");
  const int64_t F = magnitude.size(-2);
  const double n_fft = 2.0 * double(F - 1);
  torch::Tensor w = torch::ones({F, 1}, magnitude.options());
  w[0] = 0.5;
  w[F - 1] = 0.5;  // n_fft is even
  const torch::Tensor power = 2.0 * (magnitude.square() * w).sum(-2) / (n_fft * n_fft);
  return power.sqrt();
}

torch::Tensor log_loudness(const torch::Tensor& log_stft) {
  TORCH_CHECK(log_stft.dim() == 4, "log_loudness: expected [N, C, F, T]");
  const torch::Tensor mag = infer::log_stft_to_magnitude(log_stft.select(1, 0)).to(torch::kFloat64);
  return spectrogram_rms(mag).sum(-1).log();  // [N]
}

LoudnessMap compute_loudness_map(const LogStftFn& predict, const FloorGrid& grid,
                                 const geometry::Vec3& source, double yaw_deg,
                                 int64_t poses_per_batch, bool progress) {
  LoudnessMap map;
  map.grid = grid;
  map.source = source;
  map.yaw_deg = yaw_deg;
  const torch::Tensor mics = grid.positions();  // [N, 3]
  const int64_t n = mics.size(0);
  torch::Tensor values = torch::empty({n}, torch::kFloat64);
  ProgressOptions po;
  po.unit = "pos";
  po.enabled = progress;
  Progress bar("loudness map", n, po);
  const auto f64 = torch::TensorOptions().dtype(torch::kFloat64);
  const torch::Tensor src = torch::tensor({source.x, source.y, source.z}, f64).view({1, 3});
  for (int64_t i = 0; i < n; i += poses_per_batch) {
    const int64_t b = std::min(poses_per_batch, n - i);
    const torch::Tensor m = mics.narrow(0, i, b);
    const torch::Tensor log_stft =
        predict(m, src.expand({b, 3}).contiguous(), torch::full({b}, yaw_deg, f64));
    values.narrow(0, i, b).copy_(log_loudness(log_stft));
    bar.update(i + b);
  }
  bar.finish();
  map.values = values.view({int64_t(grid.z.size()), int64_t(grid.x.size())});
  return map;
}

namespace {

std::string fmt(double v, int decimals) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

void write_loudness_png(const std::string& path, const LoudnessMap& map) {
  const int nx = int(map.grid.x.size()), nz = int(map.grid.z.size());
  const torch::Tensor v = map.values.to(torch::kFloat64);
  const torch::Tensor finite = v.isfinite();
  double lo = 0, hi = 1;
  if (finite.any().item<bool>()) {
    lo = v.masked_select(finite).min().item<double>();
    hi = v.masked_select(finite).max().item<double>();
  }
  const double range = hi > lo ? hi - lo : 1.0;
  // Non-finite cells (silent predictions) draw at the bottom of the scale.
  const torch::Tensor t = ((v - lo) / range).nan_to_num(0.0, 1.0, 0.0).clamp(0.0, 1.0);
  const torch::Tensor rgb = infer::viridis(t);  // [nz, nx, 3]

  const int cell = std::max(2, 480 / std::max(nx, nz));
  const int s = 2;  // font scale
  const int left = 16 * s + 10, top = 8 + 7 * s, bottom = 24 * s / 2 + 16;
  const int map_w = nx * cell, map_h = nz * cell;
  const int bar_gap = 14, bar_w = 16;
  const std::string hi_s = fmt(hi, 2), lo_s = fmt(lo, 2);
  const int label_w = std::max(Canvas::text_width(hi_s, s), Canvas::text_width(lo_s, s));
  const int width = left + map_w + bar_gap + bar_w + 6 + label_w + 6;
  const int height = top + map_h + bottom;
  Canvas c(width, height);

  // Heat map, each cell upscaled.
  const torch::Tensor up =
      rgb.repeat_interleave(cell, 0).repeat_interleave(cell, 1).contiguous();  // [H, W, 3]
  c.paste(up, left, top);
  c.fill_rect(left - 1, top - 1, left + map_w + 1, top, 0, 0, 0);
  c.fill_rect(left - 1, top + map_h, left + map_w + 1, top + map_h + 1, 0, 0, 0);
  c.fill_rect(left - 1, top, left, top + map_h, 0, 0, 0);
  c.fill_rect(left + map_w, top, left + map_w + 1, top + map_h, 0, 0, 0);

  // Metres → pixel centre of the cell grid (cell i covers [left + i·cell, ...)).
  const double x0 = map.grid.x.front(), z0 = map.grid.z.front(), sp = map.grid.spacing;
  auto px = [&](double x) { return left + ((x - x0) / sp + 0.5) * cell; };
  auto pz = [&](double z) { return top + ((z - z0) / sp + 0.5) * cell; };

  // Ticks at whole (or half) metres.
  const double xmax = map.grid.x.back(), zmax = map.grid.z.back();
  const double extent = std::max(xmax - x0, zmax - z0);
  const double step = extent > 4 ? 1.0 : 0.5;
  const int dec = step < 1 ? 1 : 0;
  for (double x = std::ceil(x0 / step) * step; x <= xmax + 1e-9; x += step) {
    const int X = int(std::lround(px(x)));
    c.fill_rect(X, top + map_h, X + 1, top + map_h + 5, 0, 0, 0);
    const std::string l = fmt(x, dec);
    c.text(l, X - Canvas::text_width(l, s) / 2, top + map_h + 7, s, 0, 0, 0);
  }
  for (double z = std::ceil(z0 / step) * step; z <= zmax + 1e-9; z += step) {
    const int Z = int(std::lround(pz(z)));
    c.fill_rect(left - 6, Z, left - 1, Z + 1, 0, 0, 0);
    const std::string l = fmt(z, dec);
    c.text(l, left - 8 - Canvas::text_width(l, s), Z - 5 * s / 2, s, 0, 0, 0);
  }
  c.text("x (m)", left + map_w - Canvas::text_width("x (m)", s), top + map_h + 7 + 7 * s, s, 0, 0,
         0);
  c.text("z (m)", 2, 4, s, 0, 0, 0);

  // Source marker.
  const double sx = px(map.source.x), sz = pz(map.source.z);
  if (sx >= left && sx < left + map_w && sz >= top && sz < top + map_h) {
    const double r = std::max(5.0, 0.8 * cell);
    c.ring(sx, sz, r, 4.0, 0, 0, 0);
    c.ring(sx, sz, r, 2.0, 1, 1, 1);
  }

  // Colour bar: hi at the top.
  const int bx = left + map_w + bar_gap;
  const torch::Tensor ramp =
      torch::linspace(1.0, 0.0, map_h, torch::kFloat64).view({map_h, 1}).expand({map_h, bar_w});
  c.paste(infer::viridis(ramp), bx, top);
  c.text(hi_s, bx + bar_w + 4, top, s, 0, 0, 0);
  c.text(lo_s, bx + bar_w + 4, top + map_h - 5 * s, s, 0, 0, 0);
  infer::write_png(path, c.pixels());
}

void write_loudness_csv(const std::string& path, const LoudnessMap& map) {
  std::string out = "x_m,y_m,z_m,log_loudness\n";
  const torch::Tensor v = map.values.to(torch::kFloat64).contiguous();
  auto a = v.accessor<double, 2>();
  char buf[128];
  for (size_t iz = 0; iz < map.grid.z.size(); ++iz) {
    for (size_t ix = 0; ix < map.grid.x.size(); ++ix) {
      std::snprintf(buf, sizeof buf, "%.4f,%.4f,%.4f,%.6g\n", map.grid.x[ix], map.grid.height,
                    map.grid.z[iz], a[iz][ix]);
      out += buf;
    }
  }
  io::write_text_atomically(path, out);
}

std::string csv_path_for(const std::string& png_path) {
  const size_t slash = png_path.find_last_of('/');
  const size_t dot = png_path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash) ||
      dot == (slash == std::string::npos ? 0 : slash + 1)) {
    return png_path + ".csv";
  }
  return png_path.substr(0, dot) + ".csv";
}

}  // namespace neraf::render
