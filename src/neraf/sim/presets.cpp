#include "neraf/sim/presets.h"

#include "neraf/util/error.h"

namespace neraf::sim {

namespace {

Material material(Vec3 albedo, const std::string& texture, double scale_m, double contrast,
                  std::array<double, 7> absorption, double scattering) {
  Material m;
  m.albedo = albedo;
  m.texture.kind = texture;
  m.texture.scale_m = scale_m;
  m.texture.contrast = contrast;
  m.absorption = absorption;
  m.scattering = scattering;
  return m;
}

Box box(Vec3 center, Vec3 size, double yaw_deg, const std::string& mat) {
  Box b;
  b.center = center;
  b.size = size;
  b.yaw_deg = yaw_deg;
  b.material = mat;
  return b;
}

Source source(Vec3 position, double yaw_deg, const std::string& directivity) {
  Source s;
  s.position = position;
  s.yaw_deg = yaw_deg;
  s.directivity = directivity;
  return s;
}

// Absorption coefficients (125 Hz … 8 kHz) of common finishes, rounded from textbook tables.
constexpr std::array<double, 7> kWoodFloor{0.15, 0.11, 0.10, 0.07, 0.06, 0.07, 0.07};
constexpr std::array<double, 7> kPaintedPlaster{0.10, 0.08, 0.06, 0.05, 0.05, 0.05, 0.05};
constexpr std::array<double, 7> kAcousticCeiling{0.30, 0.40, 0.50, 0.60, 0.60, 0.60, 0.60};
constexpr std::array<double, 7> kWoodFurniture{0.10, 0.08, 0.07, 0.06, 0.06, 0.06, 0.06};
constexpr std::array<double, 7> kUpholstery{0.20, 0.35, 0.55, 0.70, 0.75, 0.75, 0.75};
constexpr std::array<double, 7> kBooks{0.30, 0.35, 0.40, 0.45, 0.50, 0.50, 0.50};

Scene demo() {
  Scene s;
  s.name = "demo";
  s.size = {4.0, 2.7, 3.5};
  s.materials["floor"] = material({0.55, 0.40, 0.28}, "stripes", 0.3, 0.25, kWoodFloor, 0.1);
  s.materials["ceiling"] = material({0.88, 0.88, 0.86}, "noise", 0.5, 0.12, kAcousticCeiling, 0.2);
  s.materials["wall"] = material({0.78, 0.74, 0.66}, "noise", 0.2, 0.25, kPaintedPlaster, 0.1);
  s.materials["wallpaper"] =
      material({0.50, 0.62, 0.74}, "stripes", 0.2, 0.3, kPaintedPlaster, 0.1);
  s.materials["wood"] = material({0.62, 0.42, 0.24}, "stripes", 0.08, 0.2, kWoodFurniture, 0.1);
  s.materials["fabric"] = material({0.70, 0.25, 0.20}, "checker", 0.15, 0.3, kUpholstery, 0.5);
  s.materials["shelf"] = material({0.30, 0.32, 0.38}, "checker", 0.3, 0.35, kBooks, 0.6);
  s.surfaces.wall_x0 = "wallpaper";
  s.furniture = {box({2.2, 0.375, 1.6}, {1.2, 0.75, 0.7}, 15, "wood"),
                 box({0.55, 0.4, 2.4}, {0.8, 0.8, 1.6}, 0, "fabric"),
                 box({3.55, 0.9, 0.5}, {0.6, 1.8, 0.9}, 0, "shelf")};
  // Four sources, so that the held-out 10 % (≈ 46 RIRs) can tell apart methods whose mean errors
  // differ by a tenth of a dB: with two, the split had 23 RIRs and a standard error of ≈ 0.1 dB.
  s.sources = {source({1.1, 1.2, 0.9}, 0, "omni"), source({3.0, 1.0, 2.9}, 45, "cardioid"),
               source({2.45, 0.9, 0.75}, 180, "cardioid"), source({1.75, 1.3, 2.95}, 0, "omni")};
  s.microphones.kind = "grid";
  s.microphones.grid.spacing_m = 0.55;
  s.microphones.grid.height_m = 1.5;
  s.microphones.grid.wall_margin_m = 0.5;
  // `--mics random`: new positions in the grid's plane and box, to test a run trained on the grid.
  s.microphones.random.count = 50;
  s.microphones.random.min_height_m = 1.5;
  s.microphones.random.max_height_m = 1.5;
  s.microphones.random.wall_margin_m = 0.5;
  s.cameras.train_count = 50;
  s.cameras.eval_count = 10;
  s.cameras.width = s.cameras.height = 96;
  s.cameras.fov_deg = 90;
  s.cameras.wall_margin_m = 0.3;
  s.cameras.look_jitter_m = 0.5;
  s.cameras.min_height_m = 0.9;
  s.cameras.max_height_m = 2.0;
  s.light.position = {2.0, 2.5, 1.75};
  s.light.intensity = 0.9;
  s.light.ambient = 0.25;
  s.acoustics.max_order = 8;
  s.acoustics.rir_length_s = 0.6;
  return s;
}

Scene shoebox() {
  Scene s;
  s.name = "shoebox";
  s.size = {5.0, 3.0, 4.0};
  // One absorption for every surface so Sabine's and Eyring's formulas apply directly.
  const std::array<double, 7> uniform{0.15, 0.15, 0.15, 0.15, 0.15, 0.15, 0.15};
  s.materials["floor"] = material({0.55, 0.45, 0.35}, "checker", 0.5, 0.3, uniform, 0.1);
  s.materials["ceiling"] = material({0.85, 0.85, 0.85}, "none", 0.25, 0.0, uniform, 0.1);
  s.materials["wall"] = material({0.75, 0.72, 0.68}, "noise", 0.3, 0.2, uniform, 0.1);
  s.sources = {source({2.0, 1.2, 1.0}, 0, "omni")};
  s.microphones.kind = "grid";
  s.microphones.grid.spacing_m = 1.0;
  s.microphones.grid.height_m = 1.5;
  s.microphones.grid.wall_margin_m = 0.5;
  s.microphones.random.count = 100;
  s.cameras.train_count = 30;
  s.cameras.eval_count = 10;
  s.cameras.width = s.cameras.height = 96;
  s.light.position = {2.5, 2.85, 2.0};
  s.light.intensity = 0.9;
  s.light.ambient = 0.25;
  s.acoustics.max_order = 10;
  s.acoustics.rir_length_s = 1.0;
  return s;
}

Scene furnished() {
  Scene s;
  s.name = "furnished";
  s.size = {7.0, 3.0, 6.0};
  s.materials["floor"] = material({0.50, 0.36, 0.24}, "stripes", 0.25, 0.25, kWoodFloor, 0.1);
  s.materials["ceiling"] = material({0.90, 0.90, 0.88}, "noise", 0.6, 0.1, kAcousticCeiling, 0.2);
  s.materials["wall"] = material({0.80, 0.76, 0.68}, "noise", 0.25, 0.25, kPaintedPlaster, 0.1);
  s.materials["wallpaper"] =
      material({0.45, 0.58, 0.50}, "stripes", 0.18, 0.3, kPaintedPlaster, 0.1);
  s.materials["tiles"] = material({0.70, 0.70, 0.72}, "checker", 0.3, 0.2, kPaintedPlaster, 0.1);
  s.materials["wood"] = material({0.62, 0.42, 0.24}, "stripes", 0.08, 0.2, kWoodFurniture, 0.1);
  s.materials["dark_wood"] = material({0.35, 0.22, 0.14}, "noise", 0.1, 0.3, kWoodFurniture, 0.2);
  s.materials["fabric"] = material({0.25, 0.35, 0.60}, "checker", 0.15, 0.3, kUpholstery, 0.5);
  s.materials["red_fabric"] = material({0.70, 0.22, 0.18}, "noise", 0.08, 0.3, kUpholstery, 0.5);
  s.materials["books"] = material({0.55, 0.45, 0.30}, "stripes", 0.06, 0.5, kBooks, 0.7);
  s.materials["painted"] = material({0.85, 0.83, 0.78}, "none", 0.25, 0.0, kWoodFurniture, 0.1);
  s.surfaces.wall_x0 = "wallpaper";
  s.surfaces.wall_z1 = "tiles";
  s.furniture = {box({1.0, 0.4, 3.0}, {0.9, 0.8, 2.0}, 0, "fabric"),
                 box({2.3, 0.225, 3.0}, {0.6, 0.45, 1.1}, 0, "wood"),
                 box({4.8, 0.375, 1.8}, {1.6, 0.75, 0.9}, 20, "dark_wood"),
                 box({6.75, 1.0, 3.5}, {0.4, 2.0, 1.6}, 0, "books"),
                 box({3.5, 0.45, 5.7}, {1.4, 0.9, 0.5}, 0, "painted"),
                 box({5.5, 0.45, 4.6}, {0.8, 0.9, 0.8}, -30, "red_fabric"),
                 box({0.5, 0.9, 0.5}, {0.4, 1.8, 0.4}, 45, "dark_wood")};
  s.sources = {source({2.0, 1.3, 1.5}, 0, "omni"), source({5.8, 1.1, 3.2}, 90, "cardioid")};
  s.microphones.kind = "grid";
  s.microphones.grid.spacing_m = 0.5;
  s.microphones.grid.height_m = 1.5;
  s.microphones.grid.wall_margin_m = 0.5;
  s.microphones.random.count = 500;
  s.microphones.random.min_height_m = 0.9;
  s.microphones.random.max_height_m = 1.8;
  s.microphones.random.wall_margin_m = 0.3;
  s.cameras.train_count = 100;
  s.cameras.eval_count = 20;
  s.cameras.width = s.cameras.height = 128;
  s.cameras.min_height_m = 0.9;
  s.cameras.max_height_m = 2.2;
  s.cameras.look_jitter_m = 0.8;
  s.light.position = {3.5, 2.85, 3.0};
  s.light.intensity = 0.9;
  s.light.ambient = 0.25;
  s.acoustics.max_order = 8;
  s.acoustics.rir_length_s = 0.8;
  return s;
}

}  // namespace

std::vector<std::string> preset_names() { return {"demo", "shoebox", "furnished"}; }

Scene preset_scene(const std::string& name) {
  if (name == "demo") return demo();
  if (name == "shoebox") return shoebox();
  if (name == "furnished") return furnished();
  std::string known;
  for (const auto& n : preset_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error("--preset: unknown preset \"" + name + "\"; choose one of " + known);
}

}  // namespace neraf::sim
