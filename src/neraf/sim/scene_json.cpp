#include "neraf/sim/scene_json.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "neraf/io/json_file.h"
#include "neraf/sim/microphones.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace neraf::sim {

using nlohmann::json;

namespace {

// What each value must be; shared by the type checks (parse) and the range checks (validate) so a
// user sees the same sentence whichever is violated.
constexpr const char* kThreePositive = "three positive numbers";
constexpr const char* kThreeNumbers = "three numbers";
constexpr const char* kAlbedo = "three numbers in [0, 1] (linear RGB)";
constexpr const char* kAbsorption =
    "7 numbers in [0, 1) (absorption of the octave bands 125, 250, 500, 1000, 2000, 4000, 8000 Hz)";
constexpr const char* kHeadings =
    "a non-empty list of distinct whole degrees in [0, 360) (e.g. [0, 90, 180, 270])";

struct Ctx {
  std::string origin;
};

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}
std::string index(const std::string& path, size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

[[noreturn]] void fail(const Ctx& c, const std::string& path, const std::string& message) {
  throw Error(c.origin + ": " + (path.empty() ? "" : path + ": ") + message);
}

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
std::string fmt(Vec3 v) { return "[" + fmt(v.x) + ", " + fmt(v.y) + ", " + fmt(v.z) + "]"; }

// Checks `j` is an object and has no keys outside `known`.
void check_object(const Ctx& c, const json& j, const std::string& path,
                  std::initializer_list<const char*> known) {
  if (!j.is_object())
    fail(c, path, path.empty() ? "must be a JSON object {...}" : "must be an object {...}");
  std::vector<std::string> unknown;
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return it.key() == k; }))
      unknown.push_back(json_quoted(it.key()));
  }
  if (unknown.empty()) return;
  std::string list, names;
  for (const auto& u : unknown) list += (list.empty() ? "" : ", ") + u;
  for (const char* k : known) names += (names.empty() ? "" : ", ") + std::string(k);
  fail(c, path,
       std::string(unknown.size() == 1 ? "unknown key " : "unknown keys ") + list +
           " (known keys: " + names + "); fix the spelling or remove it");
}

const json* find(const json& j, const char* key) {
  auto it = j.find(key);
  return it == j.end() ? nullptr : &*it;
}

double read_number(const Ctx& c, const json& j, const std::string& path, const std::string& what) {
  if (!j.is_number()) fail(c, path, "must be " + what);
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(c, path, "must be " + what);
  return v;
}

int read_int(const Ctx& c, const json& j, const std::string& path, const std::string& what) {
  if (!j.is_number()) fail(c, path, "must be " + what);
  const double v = j.get<double>();
  if (!std::isfinite(v) || v != std::floor(v) || std::abs(v) > 1e9)
    fail(c, path, "must be " + what);
  return static_cast<int>(v);
}

std::string read_string(const Ctx& c, const json& j, const std::string& path,
                        const std::string& what) {
  if (!j.is_string()) fail(c, path, "must be " + what);
  return j.get<std::string>();
}

Vec3 read_vec3(const Ctx& c, const json& j, const std::string& path, const std::string& what) {
  if (!j.is_array() || j.size() != 3) fail(c, path, "must be " + what);
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = read_number(c, j[i], path, what);
  return v;
}

std::vector<double> read_numbers(const Ctx& c, const json& j, const std::string& path,
                                 const std::string& what) {
  if (!j.is_array()) fail(c, path, "must be " + what);
  std::vector<double> out;
  for (const auto& e : j) out.push_back(read_number(c, e, path, what));
  return out;
}

// Convenience: assigns `out` from key `key` of object `j` when present.
template <typename T, typename Reader>
void opt(const json& j, const char* key, const std::string& path, T& out, Reader reader) {
  if (const json* v = find(j, key)) out = reader(*v, join(path, key));
}

Texture read_texture(const Ctx& c, const json& j, const std::string& path) {
  Texture t;
  if (j.is_string()) {  // shorthand: "texture": "checker"
    t.kind = j.get<std::string>();
    return t;
  }
  check_object(c, j, path, {"kind", "scale_m", "contrast"});
  opt(j, "kind", path, t.kind, [&](const json& v, const std::string& p) {
    return read_string(c, v, p, "one of \"none\", \"checker\", \"stripes\", \"noise\"");
  });
  opt(j, "scale_m", path, t.scale_m, [&](const json& v, const std::string& p) {
    return read_number(c, v, p, "a number of metres in [0.001, 1000]");
  });
  opt(j, "contrast", path, t.contrast, [&](const json& v, const std::string& p) {
    return read_number(c, v, p, "a number in [0, 1]");
  });
  return t;
}

Material read_material(const Ctx& c, const json& j, const std::string& path) {
  check_object(c, j, path, {"albedo", "texture", "absorption", "scattering"});
  Material m;
  opt(j, "albedo", path, m.albedo,
      [&](const json& v, const std::string& p) { return read_vec3(c, v, p, kAlbedo); });
  if (const json* v = find(j, "texture")) m.texture = read_texture(c, *v, join(path, "texture"));
  if (const json* v = find(j, "absorption")) {
    const auto a = read_numbers(c, *v, join(path, "absorption"), kAbsorption);
    if (a.size() != 7) fail(c, join(path, "absorption"), std::string("must be ") + kAbsorption);
    std::copy(a.begin(), a.end(), m.absorption.begin());
  }
  opt(j, "scattering", path, m.scattering, [&](const json& v, const std::string& p) {
    return read_number(c, v, p, "a number in [0, 1]");
  });
  return m;
}

std::vector<double> read_headings(const Ctx& c, const json& j, const std::string& path) {
  return read_numbers(c, j, path, kHeadings);
}

}  // namespace

geometry::YawBox furniture_box(const Box& box) {
  return {box.center, box.size * 0.5, geometry::deg_to_rad(box.yaw_deg)};
}

int furniture_containing(const Scene& scene, Vec3 p, double clearance) {
  for (size_t i = 0; i < scene.furniture.size(); ++i) {
    if (furniture_box(scene.furniture[i]).contains(p, clearance)) return static_cast<int>(i);
  }
  return -1;
}

bool inside_room(const Scene& scene, Vec3 p, double clearance) {
  for (int a = 0; a < 3; ++a) {
    if (!(p[a] >= clearance && p[a] <= scene.size[a] - clearance)) return false;
  }
  return true;
}

Scene scene_from_json(const json& j, const std::string& origin) {
  const Ctx c{origin};
  check_object(c, j, "",
               {"name", "size", "materials", "surfaces", "furniture", "sources", "microphones",
                "cameras", "light", "acoustics"});
  Scene s;
  const auto number = [&](const std::string& what) {
    return [&c, what](const json& v, const std::string& p) { return read_number(c, v, p, what); };
  };
  const auto integer = [&](const std::string& what) {
    return [&c, what](const json& v, const std::string& p) { return read_int(c, v, p, what); };
  };
  const auto string = [&](const std::string& what) {
    return [&c, what](const json& v, const std::string& p) { return read_string(c, v, p, what); };
  };
  const auto vec3 = [&](const std::string& what) {
    return [&c, what](const json& v, const std::string& p) { return read_vec3(c, v, p, what); };
  };

  opt(j, "name", "", s.name, string("a non-empty string"));
  opt(j, "size", "", s.size, vec3(kThreePositive));

  if (const json* m = find(j, "materials")) {
    if (!m->is_object()) fail(c, "materials", "must be an object {\"name\": {...}, ...}");
    for (auto it = m->begin(); it != m->end(); ++it) {
      s.materials[it.key()] = read_material(c, it.value(), "materials." + it.key());
    }
  }

  if (const json* f = find(j, "surfaces")) {
    const std::string p = "surfaces";
    check_object(c, *f, p, {"floor", "ceiling", "wall_x0", "wall_x1", "wall_z0", "wall_z1"});
    const auto name = string("a material name (a key of \"materials\")");
    opt(*f, "floor", p, s.surfaces.floor, name);
    opt(*f, "ceiling", p, s.surfaces.ceiling, name);
    opt(*f, "wall_x0", p, s.surfaces.wall_x0, name);
    opt(*f, "wall_x1", p, s.surfaces.wall_x1, name);
    opt(*f, "wall_z0", p, s.surfaces.wall_z0, name);
    opt(*f, "wall_z1", p, s.surfaces.wall_z1, name);
  }

  if (const json* f = find(j, "furniture")) {
    if (!f->is_array())
      fail(c, "furniture", "must be a list of boxes [{\"center\": ..., \"size\": ...}, ...]");
    for (size_t i = 0; i < f->size(); ++i) {
      const std::string p = index("furniture", i);
      const json& e = (*f)[i];
      check_object(c, e, p, {"center", "size", "yaw_deg", "material"});
      if (!find(e, "center") || !find(e, "size"))
        fail(c, p, "needs \"center\" and \"size\" (metres, three numbers each)");
      Box b;
      opt(e, "center", p, b.center, vec3(kThreeNumbers));
      opt(e, "size", p, b.size, vec3(kThreePositive));
      opt(e, "yaw_deg", p, b.yaw_deg, number("a number (degrees)"));
      b.material = "wall";
      opt(e, "material", p, b.material, string("a material name (a key of \"materials\")"));
      s.furniture.push_back(b);
    }
  }

  if (const json* f = find(j, "sources")) {
    if (!f->is_array()) fail(c, "sources", "must be a list of sources [{\"position\": ...}, ...]");
    for (size_t i = 0; i < f->size(); ++i) {
      const std::string p = index("sources", i);
      const json& e = (*f)[i];
      check_object(c, e, p, {"position", "yaw_deg", "directivity"});
      if (!find(e, "position")) fail(c, p, "needs \"position\" (metres, three numbers)");
      Source src;
      opt(e, "position", p, src.position, vec3(kThreeNumbers));
      opt(e, "yaw_deg", p, src.yaw_deg, number("a number (degrees)"));
      opt(e, "directivity", p, src.directivity, string("\"omni\" or \"cardioid\""));
      s.sources.push_back(src);
    }
  } else {
    Source src;
    src.position = {0.5 * s.size.x, std::min(1.2, 0.5 * s.size.y), 0.5 * s.size.z};
    s.sources.push_back(src);
  }

  if (const json* m = find(j, "microphones")) {
    const std::string p = "microphones";
    check_object(c, *m, p, {"kind", "grid", "random"});
    opt(*m, "kind", p, s.microphones.kind, string("\"grid\" or \"random\""));
    if (const json* g = find(*m, "grid")) {
      const std::string q = join(p, "grid");
      check_object(c, *g, q, {"spacing_m", "height_m", "wall_margin_m", "headings_deg"});
      auto& grid = s.microphones.grid;
      opt(*g, "spacing_m", q, grid.spacing_m, number("a positive number (metres)"));
      opt(*g, "height_m", q, grid.height_m, number("a number inside the room height (metres)"));
      opt(*g, "wall_margin_m", q, grid.wall_margin_m, number("a number >= 0 (metres)"));
      if (const json* h = find(*g, "headings_deg"))
        grid.headings_deg = read_headings(c, *h, join(q, "headings_deg"));
    }
    if (const json* r = find(*m, "random")) {
      const std::string q = join(p, "random");
      check_object(c, *r, q,
                   {"count", "min_height_m", "max_height_m", "wall_margin_m", "headings_deg"});
      auto& rnd = s.microphones.random;
      opt(*r, "count", q, rnd.count, integer("a positive whole number"));
      opt(*r, "min_height_m", q, rnd.min_height_m,
          number("a number inside the room height (metres)"));
      opt(*r, "max_height_m", q, rnd.max_height_m,
          number("a number inside the room height (metres)"));
      opt(*r, "wall_margin_m", q, rnd.wall_margin_m, number("a number >= 0 (metres)"));
      if (const json* h = find(*r, "headings_deg"))
        rnd.headings_deg = read_headings(c, *h, join(q, "headings_deg"));
    }
  }

  if (const json* m = find(j, "cameras")) {
    const std::string p = "cameras";
    check_object(c, *m, p,
                 {"train_count", "eval_count", "width", "height", "fov_deg", "wall_margin_m",
                  "look_jitter_m", "min_height_m", "max_height_m", "supersampling"});
    auto& cam = s.cameras;
    opt(*m, "train_count", p, cam.train_count, integer("a positive whole number"));
    opt(*m, "eval_count", p, cam.eval_count, integer("a whole number >= 0"));
    opt(*m, "width", p, cam.width, integer("a whole number of pixels in [8, 8192]"));
    opt(*m, "height", p, cam.height, integer("a whole number of pixels in [8, 8192]"));
    opt(*m, "fov_deg", p, cam.fov_deg, number("a horizontal field of view in [10, 170] degrees"));
    opt(*m, "wall_margin_m", p, cam.wall_margin_m, number("a number >= 0 (metres)"));
    opt(*m, "look_jitter_m", p, cam.look_jitter_m, number("a number >= 0 (metres)"));
    opt(*m, "min_height_m", p, cam.min_height_m,
        number("a number inside the room height (metres)"));
    opt(*m, "max_height_m", p, cam.max_height_m,
        number("a number inside the room height (metres)"));
    opt(*m, "supersampling", p, cam.supersampling, integer("a whole number in [1, 8]"));
  }

  s.light.position = default_light_position(s.size);
  if (const json* m = find(j, "light")) {
    const std::string p = "light";
    check_object(c, *m, p, {"position", "intensity", "ambient"});
    opt(*m, "position", p, s.light.position, vec3(kThreeNumbers));
    opt(*m, "intensity", p, s.light.intensity, number("a number in [0, 100]"));
    opt(*m, "ambient", p, s.light.ambient, number("a number in [0, 100]"));
  }

  if (const json* m = find(j, "acoustics")) {
    const std::string p = "acoustics";
    check_object(c, *m, p, {"speed_of_sound", "max_order", "rir_length_s"});
    opt(*m, "speed_of_sound", p, s.acoustics.speed_of_sound,
        number("a number of m/s in [1, 10000]"));
    opt(*m, "max_order", p, s.acoustics.max_order, integer("a whole number in [0, 60]"));
    opt(*m, "rir_length_s", p, s.acoustics.rir_length_s,
        number("a number of seconds in [0.001, 20]"));
  }

  validate_scene(s, origin);
  return s;
}

Scene load_scene(const std::string& path) { return scene_from_json(io::read_json(path), path); }

namespace {

json vec_json(Vec3 v) { return json::array({v.x, v.y, v.z}); }

void check_headings(const Ctx& c, const std::vector<double>& h, const std::string& path) {
  std::set<double> seen;
  for (double d : h) {
    if (!(d >= 0 && d < 360 && d == std::floor(d)) || !seen.insert(d).second)
      fail(c, path, std::string("must be ") + kHeadings);
  }
  if (h.empty()) fail(c, path, std::string("must be ") + kHeadings);
}

void check_height_range(const Ctx& c, const Scene& s, double lo, double hi,
                        const std::string& path) {
  if (!(lo >= kSurfaceClearanceM && lo <= hi && hi <= s.size.y - kSurfaceClearanceM))
    fail(c, path + ".min_height_m",
         "min_height_m " + fmt(lo) + " and max_height_m " + fmt(hi) + " must satisfy " +
             fmt(kSurfaceClearanceM) + " <= min <= max <= room height - " +
             fmt(kSurfaceClearanceM) + " = " + fmt(s.size.y - kSurfaceClearanceM));
}

}  // namespace

void validate_scene(const Scene& s, const std::string& origin) {
  const Ctx c{origin};
  if (s.name.empty()) fail(c, "name", "must be a non-empty string");
  if (!(is_finite(s.size) && s.size.x > 0 && s.size.y > 0 && s.size.z > 0))
    fail(c, "size",
         std::string("must be ") + kThreePositive + " (room extent in metres along x, y (up), z)");
  // Checked before anything walks the room: a 1e9 m room would otherwise make the camera and
  // microphone placement, the textures and the reverb model work at absurd scales.
  if (std::max({s.size.x, s.size.y, s.size.z}) > kMaxRoomSizeM)
    fail(c, "size",
         fmt(s.size) + " m: each side must be at most " + fmt(kMaxRoomSizeM) +
             " m (the largest halls are ~300 m); use a smaller room");
  // Every camera ray, shadow ray, microphone placement and sound path is tested against every
  // box, so 20,000 boxes would run for hours; refused before any of that starts.
  if (s.furniture.size() > kMaxFurniture)
    fail(c, "furniture",
         std::to_string(s.furniture.size()) + " boxes: at most " + std::to_string(kMaxFurniture) +
             " (each camera ray and sound path is tested against every box); merge or remove "
             "boxes");
  const std::string room = "the room [0, " + fmt(s.size.x) + "] x [0, " + fmt(s.size.y) +
                           "] x [0, " + fmt(s.size.z) + "]";

  for (const auto& [name, m] : s.materials) {
    const std::string p = "materials." + name;
    if (name.empty()) fail(c, "materials", "material names must not be empty");
    for (int i = 0; i < 3; ++i) {
      if (!(m.albedo[i] >= 0 && m.albedo[i] <= 1))
        fail(c, p + ".albedo", std::string("must be ") + kAlbedo);
    }
    const auto& t = m.texture;
    if (t.kind != "none" && t.kind != "checker" && t.kind != "stripes" && t.kind != "noise")
      fail(c, p + ".texture.kind",
           "unknown texture " + json_quoted(t.kind) +
               "; use one of \"none\", \"checker\", \"stripes\", \"noise\"");
    if (!(t.scale_m >= kMinTextureScaleM && t.scale_m <= kMaxTextureScaleM))
      fail(c, p + ".texture.scale_m", "must be a number of metres in [0.001, 1000]");
    if (!(t.contrast >= 0 && t.contrast <= 1))
      fail(c, p + ".texture.contrast", "must be a number in [0, 1]");
    for (double a : m.absorption) {
      if (!(a >= 0 && a < 1)) fail(c, p + ".absorption", std::string("must be ") + kAbsorption);
    }
    if (!(m.scattering >= 0 && m.scattering <= 1))
      fail(c, p + ".scattering", "must be a number in [0, 1]");
  }

  const auto check_material = [&](const std::string& name, const std::string& path) {
    if (s.materials.count(name)) return;
    std::string known;
    for (const auto& kv : s.materials) known += (known.empty() ? "" : ", ") + kv.first;
    fail(c, path,
         "unknown material " + json_quoted(name) + " (defined: " + known +
             "); define it under \"materials\"");
  };
  check_material(s.surfaces.floor, "surfaces.floor");
  check_material(s.surfaces.ceiling, "surfaces.ceiling");
  check_material(s.surfaces.wall_x0, "surfaces.wall_x0");
  check_material(s.surfaces.wall_x1, "surfaces.wall_x1");
  check_material(s.surfaces.wall_z0, "surfaces.wall_z0");
  check_material(s.surfaces.wall_z1, "surfaces.wall_z1");

  constexpr double kTol = 1e-9;
  for (size_t i = 0; i < s.furniture.size(); ++i) {
    const Box& b = s.furniture[i];
    const std::string p = index("furniture", i);
    if (!is_finite(b.center)) fail(c, p + ".center", std::string("must be ") + kThreeNumbers);
    if (!(is_finite(b.size) && b.size.x > 0 && b.size.y > 0 && b.size.z > 0))
      fail(c, p + ".size", std::string("must be ") + kThreePositive);
    if (!(std::abs(b.yaw_deg) <= kMaxYawDeg))
      fail(c, p + ".yaw_deg", "must be a number of degrees in [-1e6, 1e6]");
    check_material(b.material, p + ".material");
    const Vec3 h = furniture_box(b).world_half_extent();
    for (int a = 0; a < 3; ++a) {
      if (b.center[a] - h[a] < -kTol || b.center[a] + h[a] > s.size[a] + kTol)
        fail(c, p,
             "the box (center " + fmt(b.center) + ", size " + fmt(b.size) + ", yaw " +
                 fmt(b.yaw_deg) + " deg) reaches outside " + room + "; move or shrink it");
    }
  }

  const auto check_point = [&](Vec3 pos, const std::string& path, const std::string& what) {
    if (!is_finite(pos)) fail(c, path, std::string("must be ") + kThreeNumbers);
    if (!inside_room(s, pos, kSurfaceClearanceM))
      fail(c, path,
           fmt(pos) + " is outside " + room + " (or closer than " + fmt(kSurfaceClearanceM) +
               " m to a surface); move the " + what + " into the room");
    const int k = furniture_containing(s, pos, 0.0);
    if (k >= 0)
      fail(c, path,
           fmt(pos) + " is inside furniture[" + std::to_string(k) + "]; move the " + what +
               " out of the box");
  };

  if (s.sources.empty()) fail(c, "sources", "needs at least one sound source");
  for (size_t i = 0; i < s.sources.size(); ++i) {
    const Source& src = s.sources[i];
    const std::string p = index("sources", i);
    check_point(src.position, p + ".position", "source");
    if (!(std::abs(src.yaw_deg) <= kMaxYawDeg))
      fail(c, p + ".yaw_deg", "must be a number of degrees in [-1e6, 1e6]");
    if (src.directivity != "omni" && src.directivity != "cardioid")
      fail(
          c, p + ".directivity",
          "unknown directivity " + json_quoted(src.directivity) + "; use \"omni\" or \"cardioid\"");
  }

  const Microphones& mic = s.microphones;
  if (mic.kind != "grid" && mic.kind != "random")
    fail(c, "microphones.kind",
         "unknown kind " + json_quoted(mic.kind) + "; use \"grid\" or \"random\"");
  {
    const auto& g = mic.grid;
    const std::string p = "microphones.grid";
    if (!(g.spacing_m > 0 && std::isfinite(g.spacing_m)))
      fail(c, p + ".spacing_m", "must be a positive number (metres)");
    if (!(g.wall_margin_m >= 0 && std::isfinite(g.wall_margin_m)))
      fail(c, p + ".wall_margin_m", "must be a number >= 0 (metres)");
    if (!(g.height_m >= kSurfaceClearanceM && g.height_m <= s.size.y - kSurfaceClearanceM))
      fail(c, p + ".height_m", "must be inside the room height (0, " + fmt(s.size.y) + ") m");
    check_headings(c, g.headings_deg, p + ".headings_deg");
    if (mic.kind == "grid") {
      if (2 * g.wall_margin_m > std::min(s.size.x, s.size.z))
        fail(c, p + ".wall_margin_m",
             "a margin of " + fmt(g.wall_margin_m) + " m leaves no floor area in a " +
                 fmt(s.size.x) + " x " + fmt(s.size.z) + " m room; reduce it");
      // The grid's size from grid_microphone_positions' formula, before any point is made: a tiny
      // spacing (or a huge room) must be this error, not billions of points or an int overflow.
      const auto axis_count = [&](double length) {
        const double usable = length - 2 * g.wall_margin_m;
        return usable < 0 ? 0.0 : std::floor(usable / g.spacing_m + 1e-9) + 1;
      };
      const double grid_count = axis_count(s.size.x) * axis_count(s.size.z);
      if (grid_count > kMaxGridMicrophones)
        fail(c, p + ".spacing_m",
             fmt(g.spacing_m) + " m gives " + fmt(grid_count) + " grid points in a " +
                 fmt(s.size.x) + " x " + fmt(s.size.z) + " m room (the limit is " +
                 std::to_string(kMaxGridMicrophones) + "); use a larger spacing");
      const auto points = grid_microphone_positions(s);
      if (points.empty())
        fail(c, p,
             "no grid point is in free space (all inside furniture); move furniture or change "
             "spacing_m");
      if (points.size() > static_cast<size_t>(kMaxGridMicrophones))
        fail(c, p + ".spacing_m",
             "gives " + std::to_string(points.size()) + " points (the limit is " +
                 std::to_string(kMaxGridMicrophones) + "); use a larger spacing");
    }
  }
  {
    const auto& r = mic.random;
    const std::string p = "microphones.random";
    if (!(r.count >= 1 && r.count <= kMaxGridMicrophones))
      fail(c, p + ".count",
           "must be a whole number in [1, " + std::to_string(kMaxGridMicrophones) + "]");
    if (!(r.wall_margin_m >= 0 && std::isfinite(r.wall_margin_m)))
      fail(c, p + ".wall_margin_m", "must be a number >= 0 (metres)");
    check_height_range(c, s, r.min_height_m, r.max_height_m, p);
    check_headings(c, r.headings_deg, p + ".headings_deg");
    if (mic.kind == "random" &&
        2 * std::max(r.wall_margin_m, kSurfaceClearanceM) >= std::min(s.size.x, s.size.z))
      fail(c, p + ".wall_margin_m",
           "a margin of " + fmt(r.wall_margin_m) + " m leaves no floor area in a " + fmt(s.size.x) +
               " x " + fmt(s.size.z) + " m room; reduce it");
  }

  {
    const auto& cam = s.cameras;
    const std::string p = "cameras";
    if (!(cam.train_count >= 1 && cam.train_count <= 100000))
      fail(c, p + ".train_count", "must be a whole number in [1, 100000]");
    if (!(cam.eval_count >= 0 && cam.eval_count <= 100000))
      fail(c, p + ".eval_count", "must be a whole number in [0, 100000]");
    if (!(cam.width >= 8 && cam.width <= 8192))
      fail(c, p + ".width", "must be a whole number of pixels in [8, 8192]");
    if (!(cam.height >= 8 && cam.height <= 8192))
      fail(c, p + ".height", "must be a whole number of pixels in [8, 8192]");
    if (!(cam.fov_deg >= 10 && cam.fov_deg <= 170))
      fail(c, p + ".fov_deg", "must be a horizontal field of view in [10, 170] degrees");
    if (!(cam.wall_margin_m >= 0 &&
          2 * std::max(cam.wall_margin_m, kSurfaceClearanceM) < std::min(s.size.x, s.size.z)))
      fail(c, p + ".wall_margin_m", "must be >= 0 and leave floor area between the walls");
    if (!(cam.look_jitter_m >= 0 && std::isfinite(cam.look_jitter_m)))
      fail(c, p + ".look_jitter_m", "must be a number >= 0 (metres)");
    check_height_range(c, s, cam.min_height_m, cam.max_height_m, p);
    if (!(cam.supersampling >= 1 && cam.supersampling <= 8))
      fail(c, p + ".supersampling", "must be a whole number in [1, 8]");
  }

  check_point(s.light.position, "light.position", "light");
  if (!(s.light.intensity >= 0 && s.light.intensity <= kMaxLightTerm))
    fail(c, "light.intensity", "must be a number in [0, 100]");
  if (!(s.light.ambient >= 0 && s.light.ambient <= kMaxLightTerm))
    fail(c, "light.ambient", "must be a number in [0, 100]");

  const auto& ac = s.acoustics;
  // Air is 343 m/s, water ~1500, steel ~6000: beyond [1, 10000] m/s a typo is likelier.
  if (!(ac.speed_of_sound >= 1 && ac.speed_of_sound <= 10000))
    fail(c, "acoustics.speed_of_sound", "must be a number of m/s in [1, 10000] (air: 343)");
  // The simulator's own limit (rir_simulator.cpp): the image count grows as order^3.
  if (!(ac.max_order >= 0 && ac.max_order <= kMaxReflectionOrder))
    fail(c, "acoustics.max_order",
         "must be a whole number in [0, " + std::to_string(kMaxReflectionOrder) + "]");
  // At least a millisecond: shorter RIRs are under one STFT hop of either layout.
  if (!(ac.rir_length_s >= 0.001 && ac.rir_length_s <= 20))
    fail(c, "acoustics.rir_length_s", "must be a number of seconds in [0.001, 20]");
}

json scene_to_json(const Scene& s) {
  json j = json::object();
  j["name"] = s.name;
  j["size"] = vec_json(s.size);
  json mats = json::object();
  for (const auto& [name, m] : s.materials) {
    mats[name] = {{"albedo", vec_json(m.albedo)},
                  {"texture",
                   {{"kind", m.texture.kind},
                    {"scale_m", m.texture.scale_m},
                    {"contrast", m.texture.contrast}}},
                  {"absorption", m.absorption},
                  {"scattering", m.scattering}};
  }
  j["materials"] = mats;
  j["surfaces"] = {{"floor", s.surfaces.floor},     {"ceiling", s.surfaces.ceiling},
                   {"wall_x0", s.surfaces.wall_x0}, {"wall_x1", s.surfaces.wall_x1},
                   {"wall_z0", s.surfaces.wall_z0}, {"wall_z1", s.surfaces.wall_z1}};
  json furniture = json::array();
  for (const auto& b : s.furniture) {
    furniture.push_back({{"center", vec_json(b.center)},
                         {"size", vec_json(b.size)},
                         {"yaw_deg", b.yaw_deg},
                         {"material", b.material}});
  }
  j["furniture"] = furniture;
  json sources = json::array();
  for (const auto& src : s.sources) {
    sources.push_back({{"position", vec_json(src.position)},
                       {"yaw_deg", src.yaw_deg},
                       {"directivity", src.directivity}});
  }
  j["sources"] = sources;
  const auto& g = s.microphones.grid;
  const auto& r = s.microphones.random;
  j["microphones"] = {{"kind", s.microphones.kind},
                      {"grid",
                       {{"spacing_m", g.spacing_m},
                        {"height_m", g.height_m},
                        {"wall_margin_m", g.wall_margin_m},
                        {"headings_deg", g.headings_deg}}},
                      {"random",
                       {{"count", r.count},
                        {"min_height_m", r.min_height_m},
                        {"max_height_m", r.max_height_m},
                        {"wall_margin_m", r.wall_margin_m},
                        {"headings_deg", r.headings_deg}}}};
  const auto& cam = s.cameras;
  j["cameras"] = {{"train_count", cam.train_count},
                  {"eval_count", cam.eval_count},
                  {"width", cam.width},
                  {"height", cam.height},
                  {"fov_deg", cam.fov_deg},
                  {"wall_margin_m", cam.wall_margin_m},
                  {"look_jitter_m", cam.look_jitter_m},
                  {"min_height_m", cam.min_height_m},
                  {"max_height_m", cam.max_height_m},
                  {"supersampling", cam.supersampling}};
  j["light"] = {{"position", vec_json(s.light.position)},
                {"intensity", s.light.intensity},
                {"ambient", s.light.ambient}};
  j["acoustics"] = {{"speed_of_sound", s.acoustics.speed_of_sound},
                    {"max_order", s.acoustics.max_order},
                    {"rir_length_s", s.acoustics.rir_length_s}};
  return j;
}

}  // namespace neraf::sim
