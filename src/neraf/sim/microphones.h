#pragma once
// Where the simulator puts its microphones (receivers).
#include <cstdint>
#include <vector>

#include "neraf/sim/scene.h"

namespace neraf::sim {

// Microphones keep at least this distance to furniture.
constexpr double kMicFurnitureClearanceM = 0.1;

// Grid microphones: a regular floor grid at height_m, centred in the room within wall_margin_m of
// the walls (n = floor((L − 2·margin)/spacing) + 1 points per axis). Points inside furniture
// (grown by kMicFurnitureClearanceM) are skipped, like SoundSpaces' non-navigable points. Order:
// z-major rows, x within a row (index = the SoundSpaces point index).
std::vector<Vec3> grid_microphone_positions(const Scene& scene);

// Random microphones: `count` uniform positions within the margins and height range, outside
// furniture; deterministic for `seed`. Throws neraf::Error when free space is too scarce.
std::vector<Vec3> random_microphone_positions(const Scene& scene, uint64_t seed);

// The scene's microphones (grid or random per microphones.kind) and their headings.
std::vector<Vec3> microphone_positions(const Scene& scene, uint64_t seed);
const std::vector<double>& microphone_headings(const Scene& scene);

}  // namespace neraf::sim
