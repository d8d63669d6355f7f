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

// --- Partitions -----------------------------------------------------------------------------
// The simulator has one shoebox shell; interior walls are furniture boxes, which occlude every
// path segment that crosses them (edge diffraction around the cheapest silhouette edge, no
// transmission) and reflect at first order. A doorway is a gap between two boxes with a lintel
// box above it, so sound and sight pass through the gap only.

constexpr double kPartitionThicknessM = 0.12;
constexpr double kDoorHeightM = 2.1;

struct Doorway {
  double from_m, to_m;  // along the wall
};

// A full-height wall of material `mat` at x = `x` from z0 to z1, open at `doors` (sorted, inside
// [z0, z1]); a lintel fills each doorway above kDoorHeightM.
void add_wall_x(Scene& s, double x, double z0, double z1, const std::vector<Doorway>& doors,
                const std::string& mat) {
  const double h = s.size.y, t = kPartitionThicknessM;
  double z = z0;
  for (const Doorway& d : doors) {
    if (d.from_m > z)
      s.furniture.push_back(box({x, h / 2, (z + d.from_m) / 2}, {t, h, d.from_m - z}, 0, mat));
    s.furniture.push_back(box({x, (kDoorHeightM + h) / 2, (d.from_m + d.to_m) / 2},
                              {t, h - kDoorHeightM, d.to_m - d.from_m}, 0, mat));
    z = d.to_m;
  }
  if (z1 > z) s.furniture.push_back(box({x, h / 2, (z + z1) / 2}, {t, h, z1 - z}, 0, mat));
}

// The same at z = `z` from x0 to x1.
void add_wall_z(Scene& s, double z, double x0, double x1, const std::vector<Doorway>& doors,
                const std::string& mat) {
  const double h = s.size.y, t = kPartitionThicknessM;
  double x = x0;
  for (const Doorway& d : doors) {
    if (d.from_m > x)
      s.furniture.push_back(box({(x + d.from_m) / 2, h / 2, z}, {d.from_m - x, h, t}, 0, mat));
    s.furniture.push_back(box({(d.from_m + d.to_m) / 2, (kDoorHeightM + h) / 2, z},
                              {d.to_m - d.from_m, h - kDoorHeightM, t}, 0, mat));
    x = d.to_m;
  }
  if (x1 > x) s.furniture.push_back(box({(x + x1) / 2, h / 2, z}, {x1 - x, h, t}, 0, mat));
}

// Hard and soft finishes of the rooms below (absorption 125 Hz … 8 kHz, rounded textbook values).
constexpr std::array<double, 7> kCarpet{0.08, 0.24, 0.57, 0.69, 0.71, 0.73, 0.73};
constexpr std::array<double, 7> kAcousticPanel{0.50, 0.80, 0.95, 0.95, 0.95, 0.90, 0.90};
constexpr std::array<double, 7> kHeavyCurtain{0.14, 0.35, 0.55, 0.72, 0.70, 0.65, 0.65};
constexpr std::array<double, 7> kGlass{0.18, 0.06, 0.04, 0.03, 0.02, 0.02, 0.02};
constexpr std::array<double, 7> kTiles{0.01, 0.01, 0.01, 0.02, 0.02, 0.02, 0.02};

// One room split in two by a full-height partition with one doorway: for sources and listeners
// on opposite sides the direct path (and many early reflections) is blocked, so the RIR depends
// on where the wall is, not only on the distance — geometry a model must learn from the grid.
Scene occluded() {
  Scene s;
  s.name = "occluded";
  s.size = {6.0, 2.7, 4.0};
  s.materials["floor"] = material({0.55, 0.40, 0.28}, "stripes", 0.3, 0.25, kWoodFloor, 0.1);
  s.materials["ceiling"] = material({0.88, 0.88, 0.86}, "noise", 0.5, 0.12, kAcousticCeiling, 0.2);
  s.materials["wall"] = material({0.78, 0.74, 0.66}, "noise", 0.2, 0.25, kPaintedPlaster, 0.1);
  s.materials["partition"] =
      material({0.50, 0.62, 0.74}, "stripes", 0.2, 0.3, kPaintedPlaster, 0.1);
  s.materials["wood"] = material({0.62, 0.42, 0.24}, "stripes", 0.08, 0.2, kWoodFurniture, 0.1);
  s.materials["fabric"] = material({0.70, 0.25, 0.20}, "checker", 0.15, 0.3, kUpholstery, 0.5);
  // The partition at x = 3 with a 1.1 m doorway near the z = 4 wall.
  add_wall_x(s, 3.0, 0.0, 4.0, {{2.6, 3.7}}, "partition");
  s.furniture.push_back(box({1.2, 0.375, 1.2}, {1.0, 0.75, 0.6}, 0, "wood"));
  s.furniture.push_back(box({5.3, 0.4, 1.0}, {0.8, 0.8, 1.4}, 0, "fabric"));
  // Two sources in each half, away from the doorway, so most pairs across the wall are blocked.
  s.sources = {source({1.0, 1.2, 0.6}, 0, "omni"), source({2.2, 1.0, 2.0}, 90, "cardioid"),
               source({4.2, 1.2, 0.7}, 270, "cardioid"), source({5.2, 1.3, 2.6}, 0, "omni")};
  s.microphones.kind = "grid";
  s.microphones.grid.spacing_m = 0.6;
  s.microphones.grid.height_m = 1.5;
  s.microphones.grid.wall_margin_m = 0.5;
  s.microphones.random.count = 50;
  s.microphones.random.min_height_m = 1.5;
  s.microphones.random.max_height_m = 1.5;
  s.microphones.random.wall_margin_m = 0.5;
  s.cameras.train_count = 50;
  s.cameras.eval_count = 10;
  s.cameras.width = s.cameras.height = 96;
  s.cameras.min_height_m = 0.9;
  s.cameras.max_height_m = 2.0;
  s.light.position = {3.0, 2.0, 3.15};  // in the doorway, below the lintel: lights both halves
  s.light.intensity = 0.9;
  s.light.ambient = 0.35;
  s.acoustics.max_order = 8;
  s.acoustics.rir_length_s = 0.6;
  return s;
}

// RAF-like room (FurnishedRoom / EmptyRoom): the shell, materials, sources, cameras and random
// microphones of both presets; `furnished` adds the furniture. Every box is lower than the
// microphones' and cameras' lowest height minus the 0.1 m clearance, so no random microphone or
// camera is ever rejected for furniture and the same seed places them identically in both rooms.
Scene raf_room(bool furnished) {
  Scene s;
  s.name = furnished ? "furnished_room" : "empty_room";
  s.size = {6.0, 2.8, 5.0};
  s.materials["floor"] = material({0.50, 0.36, 0.24}, "stripes", 0.25, 0.25, kWoodFloor, 0.1);
  // Absorbing ceiling tiles (an office-like room): the empty room's decay stays well inside the
  // RIR (Eyring T60 ≈ 0.5 s at 1 kHz, furnished ≈ 0.35 s; docs/SCENE_FORMAT.md).
  s.materials["ceiling"] = material({0.90, 0.90, 0.88}, "checker", 0.6, 0.1, kAcousticCeiling, 0.2);
  s.materials["wall"] = material({0.80, 0.76, 0.68}, "noise", 0.25, 0.25, kPaintedPlaster, 0.1);
  s.materials["window"] = material({0.55, 0.65, 0.75}, "stripes", 0.6, 0.2, kGlass, 0.05);
  s.materials["wood"] = material({0.62, 0.42, 0.24}, "stripes", 0.08, 0.2, kWoodFurniture, 0.1);
  s.materials["dark_wood"] = material({0.35, 0.22, 0.14}, "noise", 0.1, 0.3, kWoodFurniture, 0.2);
  s.materials["fabric"] = material({0.25, 0.35, 0.60}, "checker", 0.15, 0.3, kUpholstery, 0.5);
  s.materials["rug"] = material({0.60, 0.25, 0.22}, "checker", 0.2, 0.3, kCarpet, 0.3);
  s.surfaces.wall_z0 = "window";
  if (furnished) {
    s.furniture = {box({1.1, 0.4, 2.5}, {0.9, 0.8, 2.0}, 0, "fabric"),        // sofa
                   box({2.4, 0.225, 2.5}, {0.6, 0.45, 1.1}, 0, "wood"),       // coffee table
                   box({4.6, 0.375, 1.2}, {1.6, 0.75, 0.9}, 0, "dark_wood"),  // dining table
                   box({5.6, 0.5, 3.8}, {0.6, 1.0, 1.6}, 0, "dark_wood"),     // sideboard
                   box({3.4, 0.45, 4.6}, {1.2, 0.9, 0.6}, 0, "fabric"),       // armchairs
                   box({3.6, 0.01, 2.6}, {2.0, 0.02, 1.6}, 0, "rug"),         // rug
                   box({0.6, 0.45, 0.5}, {0.5, 0.9, 0.5}, 30, "wood")};       // side table
  }
  // RAF's loudspeaker is directional; two placements facing into the room, the second low
  // (0.5 m) in front of the window behind the dining table, which in the furnished room blocks its
  // direct path to part of the room (the low furniture never blocks a path between 1.15 m and up).
  s.sources = {source({0.8, 1.2, 4.3}, 315, "cardioid"), source({4.6, 0.5, 0.4}, 180, "cardioid")};
  s.microphones.kind = "random";
  s.microphones.random.count = 300;
  s.microphones.random.min_height_m = 1.15;
  s.microphones.random.max_height_m = 1.8;
  s.microphones.random.wall_margin_m = 0.3;
  s.microphones.grid.spacing_m = 0.5;  // --mics grid: a SoundSpaces-like grid of the same room
  s.microphones.grid.height_m = 1.5;
  s.cameras.train_count = 60;
  s.cameras.eval_count = 10;
  s.cameras.width = s.cameras.height = 96;
  s.cameras.min_height_m = 1.15;
  s.cameras.max_height_m = 2.0;
  s.cameras.look_jitter_m = 0.6;
  s.light.position = {3.0, 2.65, 2.5};
  s.light.intensity = 0.9;
  s.light.ambient = 0.25;
  s.acoustics.max_order = 8;
  s.acoustics.rir_length_s = 0.8;
  return s;
}

// A small, heavily treated room (carpet, an absorbing ceiling, a curtain wall, a sofa): short decay
// (Eyring T60 ≈ 0.1 s at 1 kHz), strong direct sound. With large_live and demo, three rooms of
// different size and absorption.
Scene small_dead() {
  Scene s;
  s.name = "small_dead";
  s.size = {3.0, 2.4, 2.6};
  s.materials["floor"] = material({0.40, 0.30, 0.30}, "checker", 0.2, 0.2, kCarpet, 0.2);
  s.materials["ceiling"] = material({0.90, 0.90, 0.90}, "checker", 0.6, 0.1, kAcousticPanel, 0.3);
  s.materials["wall"] = material({0.45, 0.45, 0.50}, "noise", 0.15, 0.3, kPaintedPlaster, 0.1);
  s.materials["curtain"] = material({0.55, 0.20, 0.25}, "stripes", 0.12, 0.35, kHeavyCurtain, 0.5);
  s.materials["fabric"] = material({0.25, 0.35, 0.60}, "checker", 0.15, 0.3, kUpholstery, 0.5);
  s.surfaces.wall_x1 = "curtain";
  s.furniture = {box({0.6, 0.4, 1.3}, {0.8, 0.8, 1.6}, 0, "fabric")};
  s.sources = {source({2.3, 1.2, 0.6}, 0, "omni"), source({1.8, 1.1, 2.0}, 180, "cardioid")};
  s.microphones.kind = "grid";
  s.microphones.grid.spacing_m = 0.4;
  s.microphones.grid.height_m = 1.4;
  s.microphones.grid.wall_margin_m = 0.4;
  s.microphones.random.count = 40;
  s.microphones.random.min_height_m = 1.4;
  s.microphones.random.max_height_m = 1.4;
  s.microphones.random.wall_margin_m = 0.4;
  s.cameras.train_count = 40;
  s.cameras.eval_count = 10;
  s.cameras.width = s.cameras.height = 96;
  s.cameras.min_height_m = 0.9;
  s.cameras.max_height_m = 1.9;
  s.cameras.look_jitter_m = 0.3;
  s.light.position = {1.5, 2.25, 1.3};
  s.light.intensity = 0.9;
  s.light.ambient = 0.25;
  s.acoustics.max_order = 6;
  s.acoustics.rir_length_s = 0.4;
  return s;
}

// A large hall with hard surfaces (wood floor, plaster, a glass wall) and a block of upholstered
// seats: long decay (Eyring T60 ≈ 1.3 s at 1 kHz), late energy dominates.
Scene large_live() {
  Scene s;
  s.name = "large_live";
  s.size = {12.0, 4.5, 9.0};
  s.materials["floor"] = material({0.55, 0.40, 0.28}, "stripes", 0.4, 0.25, kWoodFloor, 0.1);
  s.materials["ceiling"] = material({0.85, 0.85, 0.82}, "noise", 0.8, 0.15, kPaintedPlaster, 0.1);
  s.materials["wall"] = material({0.72, 0.70, 0.66}, "noise", 0.5, 0.25, kPaintedPlaster, 0.1);
  s.materials["seats"] = material({0.55, 0.15, 0.20}, "checker", 0.5, 0.3, kUpholstery, 0.5);
  s.materials["window"] = material({0.55, 0.65, 0.75}, "stripes", 1.0, 0.2, kGlass, 0.05);
  s.materials["wood"] = material({0.62, 0.42, 0.24}, "stripes", 0.08, 0.2, kWoodFurniture, 0.1);
  s.surfaces.wall_x1 = "window";
  // A block of upholstered seats is the only soft surface; a wooden stage at the x = 0 end.
  s.furniture = {box({7.0, 0.45, 4.5}, {6.0, 0.9, 4.0}, 0, "seats"),
                 box({1.0, 0.3, 4.5}, {2.0, 0.6, 6.0}, 0, "wood")};
  // A talker on the stage facing the seats, and an omni source among the audience.
  s.sources = {source({1.2, 1.6, 4.0}, 270, "cardioid"), source({9.5, 1.2, 7.5}, 0, "omni")};
  s.microphones.kind = "grid";
  s.microphones.grid.spacing_m = 1.0;
  s.microphones.grid.height_m = 1.5;
  s.microphones.grid.wall_margin_m = 0.5;
  s.microphones.random.count = 80;
  s.microphones.random.min_height_m = 1.5;
  s.microphones.random.max_height_m = 1.5;
  s.microphones.random.wall_margin_m = 0.5;
  s.cameras.train_count = 60;
  s.cameras.eval_count = 10;
  s.cameras.width = s.cameras.height = 96;
  s.cameras.min_height_m = 1.0;
  s.cameras.max_height_m = 3.0;
  s.cameras.look_jitter_m = 1.5;
  s.light.position = {6.0, 4.3, 4.5};
  s.light.intensity = 0.9;
  s.light.ambient = 0.3;
  s.acoustics.max_order = 8;
  s.acoustics.rir_length_s = 1.5;
  return s;
}

// Five rooms under one 14 × 9 m shell, joined by doorways: living room (x < 8, z < 5), kitchen
// (x > 8, z < 5), two bedrooms and a bathroom along z > 5. SoundSpaces-scale data: a 0.5 m grid
// with four headings and sources in every room.
Scene apartment() {
  Scene s;
  s.name = "apartment";
  s.size = {14.0, 2.7, 9.0};
  // Carpet throughout: with plaster walls and ceiling the decay (Eyring T60 ≈ 0.4 s at 1 kHz) then
  // fits the 0.5 s RIRs, like a furnished home (a wood floor gives ≈ 1 s).
  s.materials["floor"] = material({0.55, 0.48, 0.40}, "checker", 0.3, 0.15, kCarpet, 0.2);
  s.materials["ceiling"] = material({0.90, 0.90, 0.88}, "noise", 0.6, 0.1, kPaintedPlaster, 0.1);
  s.materials["wall"] = material({0.80, 0.76, 0.68}, "noise", 0.25, 0.25, kPaintedPlaster, 0.1);
  s.materials["partition"] = material({0.72, 0.74, 0.70}, "noise", 0.2, 0.2, kPaintedPlaster, 0.1);
  s.materials["tiles"] = material({0.70, 0.70, 0.72}, "checker", 0.3, 0.2, kTiles, 0.05);
  s.materials["wood"] = material({0.62, 0.42, 0.24}, "stripes", 0.08, 0.2, kWoodFurniture, 0.1);
  s.materials["dark_wood"] = material({0.35, 0.22, 0.14}, "noise", 0.1, 0.3, kWoodFurniture, 0.2);
  s.materials["fabric"] = material({0.25, 0.35, 0.60}, "checker", 0.15, 0.3, kUpholstery, 0.5);
  s.materials["bedding"] = material({0.85, 0.82, 0.75}, "stripes", 0.2, 0.2, kUpholstery, 0.5);
  s.materials["books"] = material({0.55, 0.45, 0.30}, "stripes", 0.06, 0.5, kBooks, 0.7);
  s.surfaces.wall_x1 = "tiles";
  // Interior walls: z = 5 (doors to bedroom 1, bedroom 2, bathroom), x = 8 (living ↔ kitchen),
  // x = 5 and x = 9.5 between the rooms along z > 5 (no doors).
  add_wall_z(s, 5.0, 0.0, 14.0, {{3.4, 4.3}, {6.6, 7.5}, {11.0, 11.9}}, "partition");
  add_wall_x(s, 8.0, 0.0, 4.94, {{1.6, 2.8}}, "partition");
  add_wall_x(s, 5.0, 5.06, 9.0, {}, "partition");
  add_wall_x(s, 9.5, 5.06, 9.0, {}, "tiles");
  s.furniture.push_back(box({1.0, 0.4, 2.5}, {0.9, 0.8, 2.2}, 0, "fabric"));        // sofa
  s.furniture.push_back(box({2.4, 0.225, 2.5}, {0.6, 0.45, 1.1}, 0, "wood"));       // coffee table
  s.furniture.push_back(box({5.8, 0.375, 2.8}, {1.6, 0.75, 0.9}, 0, "dark_wood"));  // dining
  s.furniture.push_back(box({7.6, 1.0, 0.6}, {0.5, 2.0, 1.0}, 0, "books"));         // bookcase
  s.furniture.push_back(box({11.0, 0.45, 0.35}, {5.0, 0.9, 0.6}, 0, "wood"));       // counter
  s.furniture.push_back(box({11.2, 0.45, 2.6}, {1.8, 0.9, 0.9}, 0, "wood"));        // island
  s.furniture.push_back(box({1.6, 0.3, 7.4}, {1.6, 0.6, 2.0}, 0, "bedding"));       // bed 1
  s.furniture.push_back(box({4.4, 1.0, 8.6}, {1.0, 2.0, 0.6}, 0, "dark_wood"));     // wardrobe 1
  s.furniture.push_back(box({7.4, 0.3, 7.6}, {1.4, 0.6, 1.9}, 90, "bedding"));      // bed 2
  s.furniture.push_back(box({5.5, 0.375, 8.5}, {1.0, 0.75, 0.6}, 0, "wood"));       // desk
  s.furniture.push_back(box({13.0, 0.3, 7.5}, {1.6, 0.6, 0.8}, 0, "tiles"));        // bath tub
  s.sources = {source({2.0, 1.2, 1.0}, 0, "omni"),       source({4.0, 1.0, 4.0}, 180, "cardioid"),
               source({6.5, 1.3, 1.2}, 90, "omni"),      source({3.2, 1.2, 3.6}, 270, "cardioid"),
               source({9.0, 1.1, 1.4}, 270, "cardioid"), source({12.8, 1.2, 4.2}, 0, "omni"),
               source({10.0, 1.4, 3.8}, 45, "omni"),     source({1.0, 1.2, 5.8}, 180, "cardioid"),
               source({3.6, 1.0, 8.2}, 0, "omni"),       source({6.0, 1.2, 6.2}, 180, "omni"),
               source({8.6, 1.1, 8.4}, 45, "cardioid"),  source({10.4, 1.2, 6.0}, 180, "omni"),
               source({12.0, 1.3, 8.4}, 90, "cardioid"), source({7.0, 1.5, 4.4}, 0, "omni")};
  s.microphones.kind = "grid";
  s.microphones.grid.spacing_m = 0.5;
  s.microphones.grid.height_m = 1.5;
  s.microphones.grid.wall_margin_m = 0.5;
  s.microphones.random.count = 500;
  s.microphones.random.min_height_m = 1.5;
  s.microphones.random.max_height_m = 1.5;
  s.microphones.random.wall_margin_m = 0.5;
  s.cameras.train_count = 150;
  s.cameras.eval_count = 20;
  s.cameras.width = s.cameras.height = 96;
  s.cameras.min_height_m = 1.0;
  s.cameras.max_height_m = 2.0;
  s.cameras.look_jitter_m = 2.0;
  s.light.position = {4.0, 2.55, 2.5};
  s.light.intensity = 0.8;
  s.light.ambient = 0.45;  // one point light cannot reach every room; ambient keeps them visible
  s.acoustics.max_order = 8;
  s.acoustics.rir_length_s = 0.5;
  return s;
}

// RAF-scale: furnished_room heard at 5,000 random microphone positions from each of four
// placements of the directional loudspeaker = 20,000 mono RIRs.
Scene raf_large() {
  Scene s = raf_room(true);
  s.name = "raf_large";
  s.sources = {source({0.8, 1.2, 4.3}, 315, "cardioid"), source({4.6, 0.5, 0.4}, 180, "cardioid"),
               source({3.0, 1.5, 0.5}, 180, "cardioid"), source({5.5, 0.6, 2.5}, 90, "cardioid")};
  s.microphones.random.count = 5000;
  s.acoustics.rir_length_s = 0.6;  // shorter than furnished_room (disk), still above its T60
  return s;
}

}  // namespace

std::vector<std::string> preset_names() {
  return {"demo",       "shoebox",    "furnished",  "occluded",  "furnished_room",
          "empty_room", "small_dead", "large_live", "apartment", "raf_large"};
}

std::string preset_layout(const std::string& name) {
  if (name == "furnished_room" || name == "empty_room" || name == "raf_large") return "raf";
  return "soundspaces";
}

Scene preset_scene(const std::string& name) {
  if (name == "demo") return demo();
  if (name == "shoebox") return shoebox();
  if (name == "furnished") return furnished();
  if (name == "occluded") return occluded();
  if (name == "furnished_room") return raf_room(true);
  if (name == "empty_room") return raf_room(false);
  if (name == "small_dead") return small_dead();
  if (name == "large_live") return large_live();
  if (name == "apartment") return apartment();
  if (name == "raf_large") return raf_large();
  std::string known;
  for (const auto& n : preset_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error("--preset: unknown preset \"" + name + "\"; choose one of " + known);
}

}  // namespace neraf::sim
