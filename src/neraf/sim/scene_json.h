#pragma once
// Scene description ↔ JSON (the format is documented in docs/SCENE_FORMAT.md), and validation.
//
// Every key is optional (defaults: scene.h); unknown keys are errors. Every error is one line that
// starts with `origin` (the file name, or "preset demo") and the JSON path of the offending value:
//   "scene.json: furniture[2].size: must be three positive numbers".
#include <nlohmann/json.hpp>
#include <string>

#include "neraf/geometry/box.h"
#include "neraf/sim/scene.h"

namespace neraf::sim {

// Parses and validates. Missing keys take their defaults; a missing light.position becomes
// default_light_position(size); missing sources become one omni source at the room centre (1.2 m
// high, or mid-height in low rooms).
Scene scene_from_json(const nlohmann::json& json, const std::string& origin);

// Reads, parses and validates a scene file (errors start with the path).
Scene load_scene(const std::string& path);

// The fully resolved scene (every field written), parseable by scene_from_json.
nlohmann::json scene_to_json(const Scene& scene);

// Throws neraf::Error (origin + JSON path + fix) for any inconsistent value: non-positive sizes,
// absorption outside [0, 1), unknown material names, boxes reaching outside the room, sources /
// microphones / the light outside the room or inside furniture, impossible placements.
void validate_scene(const Scene& scene, const std::string& origin);

// Geometry of a furniture piece.
geometry::YawBox furniture_box(const Box& box);
// Index of the first furniture piece containing p (grown by `clearance`), or -1.
int furniture_containing(const Scene& scene, Vec3 p, double clearance = 0.0);
// True when p is inside the room with at least `clearance` to every surface.
bool inside_room(const Scene& scene, Vec3 p, double clearance = 0.0);

// Minimum distance of sources, microphones, cameras and the light to the room's surfaces.
constexpr double kSurfaceClearanceM = 0.05;

// Limits validate_scene enforces before any work (docs/SCENE_FORMAT.md): the longest room side,
// the furniture boxes, the microphone positions (grid points or random count) and the image-source
// order (the simulator's, rir_simulator.cpp). The dataset's total size is checked separately
// (check_synthesis_size, synthesize.h).
constexpr double kMaxRoomSizeM = 1000;
constexpr size_t kMaxFurniture = 1000;
constexpr int kMaxGridMicrophones = 1000000;
constexpr int kMaxReflectionOrder = 60;
// Yaw angles as timed paths bound them (docs/PATH_FORMAT.md): larger ones lose the degrees.
constexpr double kMaxYawDeg = 1e6;
// The picture is albedo · texture · (ambient + intensity · n·l), clipped to [0, 1]: beyond 100
// every lit pixel is white (the presets use 0.8–1.0 and 0.25). A texture cell under a millimetre
// is noise at any image size, one over a kilometre is flat (the presets use 0.06–0.6 m).
constexpr double kMaxLightTerm = 100;
constexpr double kMinTextureScaleM = 1e-3, kMaxTextureScaleM = 1e3;

}  // namespace neraf::sim
