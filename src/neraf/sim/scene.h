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
  double yaw_deg = 0;                // facing direction of a directional source
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
  // Headings of the binaural (SoundSpaces layout) receivers at every random position; the RAF
  // layout's microphones are omni and ignore them.
  std::vector<double> headings_deg{0, 90, 180, 270};
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
  double min_height_m = 0.8, max_height_m = 2.0;  // camera heights (clipped to the room)
  int supersampling = 2;  // n×n rays per pixel, averaged (anti-aliases texture edges)
};

struct Light {
  // A point light. Scene JSON without light.position puts it at default_light_position(size);
  // Scene values built in C++ must set it.
  Vec3 position;
  double intensity = 1.0;
  double ambient = 0.25;
};

struct Acoustics {
  double speed_of_sound = 343.0;
  int max_order = 8;          // image-source reflection order
  double rir_length_s = 1.0;  // length of every written RIR
};

// Materials every scene has unless it redefines them: the names RoomSurfaces uses by default.
inline std::map<std::string, Material> default_materials() {
  std::map<std::string, Material> m;
  m["floor"].albedo = {0.55, 0.45, 0.35};
  m["floor"].absorption = {0.02, 0.03, 0.04, 0.05, 0.05, 0.06, 0.06};
  m["ceiling"].albedo = {0.85, 0.85, 0.85};
  m["ceiling"].absorption = {0.15, 0.20, 0.25, 0.30, 0.30, 0.30, 0.30};
  m["wall"].albedo = {0.75, 0.72, 0.68};
  m["wall"].absorption = {0.05, 0.06, 0.07, 0.08, 0.09, 0.10, 0.10};
  return m;
}

// Just below the ceiling centre.
inline Vec3 default_light_position(Vec3 room_size) {
  return {0.5 * room_size.x, room_size.y - 0.15, 0.5 * room_size.z};
}

struct Scene {
  std::string name = "scene";
  Vec3 size{5, 3, 4};
  std::map<std::string, Material> materials = default_materials();
  RoomSurfaces surfaces;
  std::vector<Box> furniture;
  std::vector<Source> sources;
  Microphones microphones;
  Cameras cameras;
  Light light;
  Acoustics acoustics;
};

}  // namespace neraf::sim
