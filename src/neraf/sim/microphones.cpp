#include "neraf/sim/microphones.h"

#include <cmath>

#include "neraf/sim/scene_json.h"
#include "neraf/sim/seeded_random.h"
#include "neraf/util/error.h"

namespace neraf::sim {

namespace {

// Grid coordinates along one axis of length `length`, centred.
std::vector<double> axis_points(double length, double margin, double spacing) {
  const double usable = length - 2 * margin;
  if (usable < 0) return {};
  const int n = static_cast<int>(std::floor(usable / spacing + 1e-9)) + 1;
  const double start = 0.5 * (length - (n - 1) * spacing);
  std::vector<double> out(n);
  for (int i = 0; i < n; ++i) out[i] = start + i * spacing;
  return out;
}

}  // namespace

std::vector<Vec3> grid_microphone_positions(const Scene& scene) {
  const auto& g = scene.microphones.grid;
  const auto xs = axis_points(scene.size.x, g.wall_margin_m, g.spacing_m);
  const auto zs = axis_points(scene.size.z, g.wall_margin_m, g.spacing_m);
  std::vector<Vec3> out;
  for (double z : zs) {
    for (double x : xs) {
      const Vec3 p{x, g.height_m, z};
      if (!inside_room(scene, p, kSurfaceClearanceM)) continue;
      if (furniture_containing(scene, p, kMicFurnitureClearanceM) >= 0) continue;
      out.push_back(p);
    }
  }
  return out;
}

std::vector<Vec3> random_microphone_positions(const Scene& scene, uint64_t seed) {
  const auto& r = scene.microphones.random;
  SeededRandom rng(derive_seed(seed, "microphones-random"));
  const double m = std::max(r.wall_margin_m, kSurfaceClearanceM);
  std::vector<Vec3> out;
  out.reserve(r.count);
  const int64_t max_tries = 1000 * int64_t(r.count) + 1000;
  int64_t tries = 0;
  while (static_cast<int>(out.size()) < r.count) {
    if (++tries > max_tries)
      throw Error("microphones.random: could not place " + std::to_string(r.count) +
                  " microphones outside the furniture; reduce wall_margin_m or the furniture");
    const Vec3 p{rng.uniform(m, scene.size.x - m), rng.uniform(r.min_height_m, r.max_height_m),
                 rng.uniform(m, scene.size.z - m)};
    if (furniture_containing(scene, p, kMicFurnitureClearanceM) >= 0) continue;
    out.push_back(p);
  }
  return out;
}

std::vector<Vec3> microphone_positions(const Scene& scene, uint64_t seed) {
  return scene.microphones.kind == "random" ? random_microphone_positions(scene, seed)
                                            : grid_microphone_positions(scene);
}

const std::vector<double>& microphone_headings(const Scene& scene) {
  return scene.microphones.kind == "random" ? scene.microphones.random.headings_deg
                                            : scene.microphones.grid.headings_deg;
}

}  // namespace neraf::sim
