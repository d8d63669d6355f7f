#pragma once
// Photos of a scene by ray casting (no neural rendering): the room's six inner faces and the
// furniture boxes, Lambertian shading from one point light (with hard shadows cast by furniture)
// plus ambient light, procedural textures in the coordinates of the hit face, sRGB 8-bit output.
//
// Linear radiance of a hit:  albedo · texture(u, v) · (ambient + intensity · max(0, n·l) · visible)
// with n the surface normal facing the room, l the unit direction to the light and `visible` 0 when
// a furniture box blocks the segment to the light. No distance falloff (the light acts like a large
// lamp, so the whole room is usefully lit). Each pixel averages supersampling² rays on a regular
// sub-pixel grid in linear light, is clamped to [0, 1], sRGB-encoded and rounded to 8 bits.
#include <cstdint>
#include <vector>

#include "neraf/geometry/box.h"
#include "neraf/sim/cameras.h"
#include "neraf/sim/scene.h"

namespace neraf::sim {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> pixels;  // [height, width, 3] row-major, sRGB
};

// Brightness factor in [1 − contrast, 1] of a texture at face coordinates (u, v) in metres.
// `face_id` decorrelates the noise of different faces. checker: squares of side scale_m, the odd
// ones darkened; stripes: period scale_m along u, the second half darkened; noise: two octaves of
// smooth value noise with cell size scale_m.
double texture_factor(const Texture& texture, double u, double v, uint32_t face_id);

// sRGB transfer function of a linear value in [0, 1].
double linear_to_srgb(double linear);
uint8_t to_8bit(double srgb);  // round(clamp(srgb, 0, 1) · 255)

class ImageRenderer {
 public:
  explicit ImageRenderer(const Scene& scene);  // the scene must be valid (validate_scene)

  // Renders one photo; OpenMP over rows; the result does not depend on the thread count.
  RgbImage render(const CameraView& view, int supersampling) const;

  struct Hit {
    double t = 0;         // distance along the (unit) ray
    Vec3 point, normal;   // normal faces the side the ray came from
    int surface = -1;     // 0..5 room faces (x0, x1, floor, ceiling, z0, z1), 6 + i furniture[i]
    double u = 0, v = 0;  // face coordinates (metres) for the texture
    uint32_t face_id = 0;
    const Material* material = nullptr;
  };
  // Nearest surface along the unit ray from `origin` (inside the room). Always hits.
  Hit intersect(Vec3 origin, Vec3 direction) const;
  // Linear RGB radiance seen along a unit ray.
  Vec3 trace(Vec3 origin, Vec3 direction) const;

 private:
  bool shadowed(Vec3 point, Vec3 to_light, double distance) const;

  const Scene& scene_;
  std::vector<geometry::YawBox> boxes_;
  std::vector<const Material*> box_materials_;
  const Material* room_materials_[6];
};

}  // namespace neraf::sim
