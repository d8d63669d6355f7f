// Picture renderer: analytic Lambertian pixels, shadows, textures, cameras, determinism.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>

#include "neraf/geometry/pose.h"
#include "neraf/sim/cameras.h"
#include "neraf/sim/image_renderer.h"
#include "neraf/sim/presets.h"
#include "neraf/sim/scene_json.h"

namespace neraf::sim {
namespace {

// sRGB 8-bit of a linear value, written out independently of the renderer.
int expected_8bit(double linear) {
  const double c = std::min(1.0, std::max(0.0, linear));
  const double s = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1 / 2.4) - 0.055;
  return static_cast<int>(std::floor(s * 255 + 0.5));
}

// 4 × 3 × 4 m room; the wall at x = 4 has an untextured orange material.
Scene wall_scene() {
  Scene s;
  s.size = {4, 3, 4};
  Material target;
  target.albedo = {0.8, 0.5, 0.2};
  s.materials["target"] = target;
  s.surfaces.wall_x1 = "target";
  s.sources = {Source{}};
  s.sources[0].position = {1, 1, 1};
  s.light.position = {2, 2.8, 2};
  s.light.intensity = 0.9;
  s.light.ambient = 0.2;
  s.cameras.width = s.cameras.height = 33;
  s.cameras.fov_deg = 90;
  validate_scene(s, "test");
  return s;
}

CameraView camera_facing_x1(const Scene& s) {
  return {geometry::look_at({2, 1.5, 2}, {4, 1.5, 2}), camera_intrinsics(s.cameras)};
}

const uint8_t* pixel(const RgbImage& img, int x, int y) {
  return &img.pixels[(size_t(y) * img.width + x) * 3];
}

TEST(RenderImage, WallPixelIsLambertianUnderThePointLight) {
  const Scene s = wall_scene();
  const ImageRenderer r(s);
  const CameraView view = camera_facing_x1(s);
  const RgbImage img = r.render(view, 1);
  ASSERT_EQ(img.width, 33);
  ASSERT_EQ(img.pixels.size(), 33u * 33u * 3u);
  const double f = view.intrinsics.fx;
  EXPECT_DOUBLE_EQ(f, 16.5);  // (33 / 2) / tan(45°)
  // Pixel (px, py): camera-frame direction ((px + .5 − 16.5)/f, −(py + .5 − 16.5)/f, −1); the
  // camera looks along +x with right = +z and up = +y, so the world direction is (1, dy, dx) and
  // the ray meets the wall x = 4 at (4, 1.5 + 2·dy, 2 + 2·dx), where the normal is (−1, 0, 0).
  for (auto [px, py] : {std::pair{16, 16}, std::pair{3, 28}, std::pair{30, 5}, std::pair{10, 12}}) {
    const double dx = (px + 0.5 - 16.5) / f, dy = -(py + 0.5 - 16.5) / f;
    const geometry::Vec3 hit{4, 1.5 + 2 * dy, 2 + 2 * dx};
    const geometry::Vec3 l = normalized(s.light.position - hit);
    const double cos_theta = -l.x;
    const geometry::Vec3 albedo{0.8, 0.5, 0.2};
    for (int c = 0; c < 3; ++c) {
      const double linear = albedo[c] * (0.2 + 0.9 * cos_theta);
      EXPECT_NEAR(pixel(img, px, py)[c], expected_8bit(linear), 1)
          << px << "," << py << " channel " << c;
    }
  }
  // The centre pixel exactly: cos θ = 2 / sqrt(2² + 1.3²).
  const double cos_c = 2 / std::sqrt(4 + 1.3 * 1.3);
  EXPECT_EQ(pixel(img, 16, 16)[0], expected_8bit(0.8 * (0.2 + 0.9 * cos_c)));
  EXPECT_EQ(pixel(img, 16, 16)[1], expected_8bit(0.5 * (0.2 + 0.9 * cos_c)));
  EXPECT_EQ(pixel(img, 16, 16)[2], expected_8bit(0.2 * (0.2 + 0.9 * cos_c)));
}

TEST(RenderImage, FurnitureCastsHardShadows) {
  Scene s = wall_scene();
  // A small box halfway between the light and the wall point the centre ray sees, off that ray.
  Box b;
  b.center = {3, 2.15, 2};
  b.size = {0.2, 0.2, 0.2};
  b.material = "wall";
  s.furniture = {b};
  validate_scene(s, "test");
  const RgbImage img = ImageRenderer(s).render(camera_facing_x1(s), 1);
  EXPECT_EQ(pixel(img, 16, 16)[0], expected_8bit(0.8 * 0.2));  // ambient only
  EXPECT_EQ(pixel(img, 16, 16)[1], expected_8bit(0.5 * 0.2));
  // Far from the shadow the wall is lit again.
  EXPECT_GT(pixel(img, 28, 16)[0], expected_8bit(0.8 * 0.2) + 20);
}

TEST(RenderImage, BoxFacesAreHitWithTheirYaw) {
  Scene s = wall_scene();
  Box b;
  b.center = {3, 1.5, 2};
  b.size = {0.5, 0.5, 0.5};
  b.yaw_deg = 45;
  b.material = "wall";
  s.furniture = {b};
  const ImageRenderer r(s);
  // Along +x the rotated cube is entered at its corner edge: x = 3 − 0.25·√2.
  const auto hit = r.intersect({2, 1.5, 2}, {1, 0, 0});
  EXPECT_EQ(hit.surface, 6);
  EXPECT_NEAR(hit.t, 1 - 0.25 * std::sqrt(2.0), 1e-12);
  // Off the edge by 0.1 m in z the face normal is the rotated local axis.
  const auto face = r.intersect({2, 1.5, 2.1}, {1, 0, 0});
  EXPECT_EQ(face.surface, 6);
  EXPECT_NEAR(std::abs(face.normal.x), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(std::abs(face.normal.z), std::sqrt(0.5), 1e-12);
  EXPECT_LT(face.normal.x, 0);  // facing the ray
  // Room faces: the floor straight down.
  const auto floor = r.intersect({1, 1, 1}, {0, -1, 0});
  EXPECT_EQ(floor.surface, 2);
  EXPECT_DOUBLE_EQ(floor.t, 1);
  EXPECT_DOUBLE_EQ(floor.normal.y, 1);
}

TEST(RenderImage, TextureFactors) {
  Texture none;
  EXPECT_EQ(texture_factor(none, 0.3, 0.7, 1), 1.0);
  Texture checker{"checker", 0.5, 0.4};
  EXPECT_DOUBLE_EQ(texture_factor(checker, 0.1, 0.1, 0), 1.0);
  EXPECT_DOUBLE_EQ(texture_factor(checker, 0.6, 0.1, 0), 0.6);
  EXPECT_DOUBLE_EQ(texture_factor(checker, 0.6, 0.6, 0), 1.0);
  EXPECT_DOUBLE_EQ(texture_factor(checker, -0.1, 0.1, 0), 0.6);
  Texture stripes{"stripes", 1.0, 0.5};
  EXPECT_DOUBLE_EQ(texture_factor(stripes, 0.2, 5, 0), 1.0);
  EXPECT_DOUBLE_EQ(texture_factor(stripes, 0.7, -3, 0), 0.5);
  Texture noise{"noise", 0.2, 0.3};
  double lo = 1, hi = 0;
  for (int i = 0; i < 1000; ++i) {
    const double f = texture_factor(noise, 0.013 * i, 0.007 * i, 3);
    lo = std::min(lo, f), hi = std::max(hi, f);
    EXPECT_GE(f, 0.7 - 1e-12);
    EXPECT_LE(f, 1.0);
  }
  EXPECT_GT(hi - lo, 0.1);  // it varies
  EXPECT_NE(texture_factor(noise, 0.31, 0.17, 3),
            texture_factor(noise, 0.31, 0.17, 4));  // per face
  // Continuous: small steps give small changes.
  EXPECT_NEAR(texture_factor(noise, 0.5, 0.5, 3), texture_factor(noise, 0.5001, 0.5, 3), 1e-3);
}

TEST(RenderImage, SrgbEncoding) {
  EXPECT_EQ(to_8bit(linear_to_srgb(0.0)), 0);
  EXPECT_EQ(to_8bit(linear_to_srgb(1.0)), 255);
  EXPECT_EQ(to_8bit(linear_to_srgb(2.0)), 255);
  EXPECT_EQ(to_8bit(linear_to_srgb(0.21586)), 128);   // sRGB 128 ≈ linear 0.2159
  EXPECT_NEAR(linear_to_srgb(0.002), 0.02584, 1e-6);  // linear segment
}

TEST(RenderImage, DeterministicForAnyThreadCount) {
  const Scene s = preset_scene("demo");
  const auto cams = place_cameras(s, 2, 7);
  const ImageRenderer r(s);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const RgbImage a = r.render(cams[1], 2);
  omp_set_num_threads(2);
  const RgbImage b = r.render(cams[1], 2);
  omp_set_num_threads(saved);
  EXPECT_EQ(a.pixels, b.pixels);
  // A textured, lit room is not a flat picture.
  int lo = 255, hi = 0;
  for (uint8_t v : a.pixels) lo = std::min<int>(lo, v), hi = std::max<int>(hi, v);
  EXPECT_GT(hi - lo, 60);
}

TEST(Cameras, PlacedNearTheWallsLookingIntoTheRoom) {
  const Scene s = preset_scene("demo");
  const auto cams = place_cameras(s, 200, 42);
  ASSERT_EQ(cams.size(), 200u);
  const auto& c = s.cameras;
  for (const auto& v : cams) {
    const auto p = v.pose.position;
    EXPECT_TRUE(inside_room(s, p, 0.05));
    EXPECT_GE(p.y, c.min_height_m);
    EXPECT_LE(p.y, c.max_height_m);
    const double wall_dist = std::min({p.x, s.size.x - p.x, p.z, s.size.z - p.z});
    EXPECT_NEAR(wall_dist, c.wall_margin_m, 1e-9);
    EXPECT_LT(furniture_containing(s, p, 0.1), 0);
    // Looks within look_jitter of the centre: the ray along the view axis passes near it.
    const geometry::Vec3 to_centre = s.size * 0.5 - p;
    const double along = dot(to_centre, v.pose.forward());
    EXPECT_GT(along, 0);
    const double off = norm(to_centre - v.pose.forward() * along);
    EXPECT_LE(off, std::sqrt(3.0) * c.look_jitter_m + 1e-9);
    // Orthonormal, right-handed camera frame; +y up in the picture.
    EXPECT_NEAR(norm(v.pose.right), 1, 1e-12);
    EXPECT_NEAR(dot(v.pose.right, v.pose.up), 0, 1e-12);
    EXPECT_NEAR(dot(cross(v.pose.right, v.pose.up), v.pose.back), 1, 1e-12);
    EXPECT_GT(v.pose.up.y, 0);
    EXPECT_NEAR(v.pose.right.y, 0, 1e-12);
  }
  // Seeded: same seed same poses, another seed other poses.
  const auto again = place_cameras(s, 200, 42), other = place_cameras(s, 200, 43);
  EXPECT_EQ(again[17].pose.position.x, cams[17].pose.position.x);
  EXPECT_EQ(again[17].pose.back.z, cams[17].pose.back.z);
  EXPECT_NE(other[17].pose.position.x, cams[17].pose.position.x);
}

TEST(Cameras, IntrinsicsAndPixelRays) {
  Cameras c;
  c.width = 128;
  c.height = 96;
  c.fov_deg = 60;
  const auto k = camera_intrinsics(c);
  EXPECT_NEAR(k.fx, 64 / std::tan(geometry::deg_to_rad(30)), 1e-12);
  EXPECT_EQ(k.fx, k.fy);
  EXPECT_EQ(k.cx, 64);
  EXPECT_EQ(k.cy, 48);
  const CameraView v{geometry::look_at({1, 1, 1}, {1, 1, 0}), k};  // looking along −z
  const auto centre = pixel_ray_direction(v, 64, 48);
  EXPECT_NEAR(centre.z, -1, 1e-12);
  // The left image edge is fov/2 to the left (−x), the top edge is up (+y).
  const auto left = pixel_ray_direction(v, 0, 48);
  EXPECT_NEAR(std::atan2(-left.x, -left.z), geometry::deg_to_rad(30), 1e-12);
  EXPECT_GT(pixel_ray_direction(v, 64, 0).y, 0);
}

}  // namespace
}  // namespace neraf::sim
