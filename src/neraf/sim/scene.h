#pragma once
// The simulator's scene description (documented for users in docs/SCENE_FORMAT.md).
//
// World frame: right-handed, metres, **y up**; the room occupies [0, size.x] × [0, size.y] ×
// [0, size.z]. A heading (microphone yaw, source yaw) of θ degrees is a rotation by θ about +y of
// the forward direction −z, i.e. forward(θ) = (−sin θ, 0, −cos θ) (Habitat / SoundSpaces
// convention; θ = 90° faces −x). The listener's left ear points along forward(θ + 90°).
#include <array>
#include <map>
#include <string>
#include <vector>

#include "neraf/geometry/vec.h"

namespace neraf::sim {

using geometry::Vec3;

// Octave bands of the acoustic material data.
constexpr std::array<double, 7> kOctaveBandsHz = {125, 250, 500, 1000, 2000, 4000, 8000};

struct Texture {
  std::string kind = "none";  // "none" | "checker" | "stripes" | "noise"
  double scale_m = 0.25;      // size of one checker square / stripe period / noise cell
  double contrast = 0.3;      // relative brightness variation in [0, 1]
};

struct Material {
  Vec3 albedo{0.7, 0.7, 0.7};  // linear RGB in [0, 1]
  Texture texture;
  std::array<double, 7> absorption{0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1};  // per octave band
  double scattering = 0.1;
};

struct Box {  // a furniture piece: axis-aligned in its own frame, rotated by yaw about +y
  Vec3 center;
  Vec3 size;
  double yaw_deg = 0;
  std::string material;
};

struct RoomSurfaces {  // material names for the six faces of the room
  std::string floor = "floor", ceiling = "ceiling";
  std::string wall_x0 = "wall", wall_x1 = "wall", wall_z0 = "wall", wall_z1 = "wall";
};

struct Source {
  Vec3 position;
  double yaw_deg = 0;              // facing direction of a directional source
  std::string directivity = "omni";  // "omni" | "cardioid"
};

struct MicrophoneGrid {  // SoundSpaces-like: a floor grid, every point with the four headings
  double spacing_m = 0.5;
  double height_m = 1.5;
  double wall_margin_m = 0.5;
  std::vector<double> headings_deg{0, 90, 180, 270};
};

struct RandomMicrophones {  // RAF-like: omni microphones at random positions
  int count = 200;
  double min_height_m = 0.8, max_height_m = 1.8;
  double wall_margin_m = 0.4;
};

struct Microphones {
  std::string kind = "grid";  // "grid" | "random"
  MicrophoneGrid grid;
  RandomMicrophones random;
};

struct Cameras {  // placed near the walls looking at the room centre with a random offset
  int train_count = 60, eval_count = 10;
  int width = 96, height = 96;
  double fov_deg = 90;
  double wall_margin_m = 0.3;
  double look_jitter_m = 0.5;
};

struct Light {
  Vec3 position;      // a point light (defaults to just below the ceiling centre)
  double intensity = 1.0;
  double ambient = 0.25;
};

struct Acoustics {
  double speed_of_sound = 343.0;
  int max_order = 8;           // image-source reflection order
  double rir_length_s = 1.0;   // length of every written RIR
};

struct Scene {
  std::string name = "scene";
  Vec3 size{5, 3, 4};
  std::map<std::string, Material> materials;
  RoomSurfaces surfaces;
  std::vector<Box> furniture;
  std::vector<Source> sources;
  Microphones microphones;
  Cameras cameras;
  Light light;
  Acoustics acoustics;
};

}  // namespace neraf::sim
