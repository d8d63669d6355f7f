#include "neraf/sim/image_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "neraf/sim/scene_json.h"

namespace neraf::sim {

namespace {

uint32_t hash3(int32_t a, int32_t b, uint32_t c) {
  uint32_t h = static_cast<uint32_t>(a) * 0x8da6b343u ^ static_cast<uint32_t>(b) * 0xd8163841u ^
               c * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}

double lattice(int32_t i, int32_t j, uint32_t face) {
  return (hash3(i, j, face) >> 8) * (1.0 / 16777216.0);
}

// Smooth value noise in [0, 1] with unit cell size.
double value_noise(double x, double y, uint32_t face) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto i = static_cast<int32_t>(fx), j = static_cast<int32_t>(fy);
  const double tx = x - fx, ty = y - fy;
  const double sx = tx * tx * (3 - 2 * tx), sy = ty * ty * (3 - 2 * ty);
  const double a = lattice(i, j, face), b = lattice(i + 1, j, face);
  const double c = lattice(i, j + 1, face), d = lattice(i + 1, j + 1, face);
  return (a + (b - a) * sx) * (1 - sy) + (c + (d - c) * sx) * sy;
}

constexpr double kEps = 1e-9;

}  // namespace

double texture_factor(const Texture& t, double u, double v, uint32_t face_id) {
  if (t.kind == "checker") {
    const auto parity = static_cast<int64_t>(std::floor(u / t.scale_m)) +
                        static_cast<int64_t>(std::floor(v / t.scale_m));
    return (parity & 1) ? 1.0 - t.contrast : 1.0;
  }
  if (t.kind == "stripes") {
    const double f = u / t.scale_m - std::floor(u / t.scale_m);
    return f >= 0.5 ? 1.0 - t.contrast : 1.0;
  }
  if (t.kind == "noise") {
    const double n =
        0.65 * value_noise(u / t.scale_m, v / t.scale_m, face_id) +
        0.35 * value_noise(2 * u / t.scale_m, 2 * v / t.scale_m, face_id ^ 0x5bd1e995u);
    return 1.0 - t.contrast * n;
  }
  return 1.0;
}

double linear_to_srgb(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
}

uint8_t to_8bit(double srgb) {
  return static_cast<uint8_t>(std::lround(std::clamp(srgb, 0.0, 1.0) * 255.0));
}

ImageRenderer::ImageRenderer(const Scene& scene) : scene_(scene) {
  const auto material = [&](const std::string& name) { return &scene.materials.at(name); };
  room_materials_[0] = material(scene.surfaces.wall_x0);
  room_materials_[1] = material(scene.surfaces.wall_x1);
  room_materials_[2] = material(scene.surfaces.floor);
  room_materials_[3] = material(scene.surfaces.ceiling);
  room_materials_[4] = material(scene.surfaces.wall_z0);
  room_materials_[5] = material(scene.surfaces.wall_z1);
  for (const Box& b : scene.furniture) {
    boxes_.push_back(furniture_box(b));
    box_materials_.push_back(material(b.material));
  }
}

ImageRenderer::Hit ImageRenderer::intersect(Vec3 o, Vec3 d) const {
  Hit hit;
  hit.t = std::numeric_limits<double>::infinity();
  // Leaving the room: the nearest of the three faces the ray heads towards.
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-300) continue;
    const bool towards_max = d[a] > 0;
    const double t = ((towards_max ? scene_.size[a] : 0.0) - o[a]) / d[a];
    if (t < hit.t) {
      hit.t = std::max(t, 0.0);
      hit.surface = 2 * a + (towards_max ? 1 : 0);
    }
  }
  const int a = hit.surface / 2;
  hit.point = o + d * hit.t;
  hit.point[a] = (hit.surface & 1) ? scene_.size[a] : 0.0;  // exactly on the face
  Vec3 n{0, 0, 0};
  n[a] = (hit.surface & 1) ? -1.0 : 1.0;  // facing into the room
  hit.normal = n;
  // Room face index: x0, x1, floor (y0), ceiling (y1), z0, z1 — the order of room_materials_.
  hit.material = room_materials_[hit.surface];
  if (a == 0) hit.u = hit.point.z, hit.v = hit.point.y;
  if (a == 1) hit.u = hit.point.x, hit.v = hit.point.z;
  if (a == 2) hit.u = hit.point.x, hit.v = hit.point.y;
  hit.face_id = static_cast<uint32_t>(hit.surface);

  for (size_t i = 0; i < boxes_.size(); ++i) {
    geometry::BoxHit bh;
    if (!geometry::intersect(boxes_[i], o, d, 0.0, hit.t, &bh)) continue;
    const auto& box = boxes_[i];
    hit.t = bh.t;
    hit.point = o + d * bh.t;
    hit.normal = box.dir_to_world(bh.normal_local);
    hit.surface = 6 + static_cast<int>(i);
    hit.material = box_materials_[i];
    // Face coordinates in the box's own frame (from its minimum corner), so textures follow the
    // box.
    const Vec3 l = box.to_local(hit.point) + box.half;
    if (bh.axis == 0) hit.u = l.z, hit.v = l.y;
    if (bh.axis == 1) hit.u = l.x, hit.v = l.z;
    if (bh.axis == 2) hit.u = l.x, hit.v = l.y;
    hit.face_id =
        static_cast<uint32_t>(6 + 6 * i + 2 * bh.axis + (bh.normal_local[bh.axis] > 0 ? 1 : 0));
  }
  return hit;
}

bool ImageRenderer::shadowed(Vec3 p, Vec3 to_light, double distance) const {
  // The room is convex and contains the light, so only furniture can block it.
  for (const auto& box : boxes_) {
    if (geometry::intersect(box, p, to_light, kEps, distance - kEps, nullptr)) return true;
  }
  return false;
}

Vec3 ImageRenderer::trace(Vec3 o, Vec3 d) const {
  const Hit hit = intersect(o, d);
  const Material& m = *hit.material;
  const double tex = texture_factor(m.texture, hit.u, hit.v, hit.face_id);
  const Vec3 to_light = scene_.light.position - hit.point;
  const double dist = norm(to_light);
  const Vec3 l = dist > 0 ? to_light / dist : Vec3{0, 1, 0};
  const double cos_theta = dot(hit.normal, l);
  double direct = 0;
  if (cos_theta > 0) {
    // Start the shadow ray just off the surface so it does not re-hit its own face.
    const Vec3 start = hit.point + hit.normal * 1e-7;
    if (!shadowed(start, l, dist)) direct = scene_.light.intensity * cos_theta;
  }
  return m.albedo * (tex * (scene_.light.ambient + direct));
}

RgbImage ImageRenderer::render(const CameraView& view, int supersampling) const {
  const int w = view.intrinsics.width, h = view.intrinsics.height;
  const int n = std::max(1, supersampling);
  RgbImage img;
  img.width = w;
  img.height = h;
  img.pixels.assign(size_t(w) * h * 3, 0);
  const Vec3 origin = view.pose.position;
#pragma omp parallel for schedule(dynamic, 4)
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      Vec3 sum{0, 0, 0};
      for (int sy = 0; sy < n; ++sy) {
        for (int sx = 0; sx < n; ++sx) {
          const double u = x + (sx + 0.5) / n, v = y + (sy + 0.5) / n;
          sum = sum + trace(origin, pixel_ray_direction(view, u, v));
        }
      }
      sum = sum / double(n * n);
      uint8_t* px = &img.pixels[(size_t(y) * w + x) * 3];
      for (int c = 0; c < 3; ++c) px[c] = to_8bit(linear_to_srgb(sum[c]));
    }
  }
  return img;
}

}  // namespace neraf::sim
