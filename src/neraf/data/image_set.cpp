#include "neraf/data/image_set.h"

#include <omp.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "neraf/io/atomic_file.h"
#include "neraf/io/json_file.h"
#include "neraf/io/png.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"
#include "neraf/util/log.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data {
namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

// Largest |camera position| accepted (the scene's units, metres for every dataset neraf reads),
// the bound of every other pose file (rir_check.h).
constexpr double kMaxAbsTranslation = 1e4;

struct Frame {
  int json_index = 0;     // index in transforms.json "frames" (what users can find in the file)
  std::string file_path;  // as written in the json
  std::string path;       // resolved on disk
  Intrinsics intr;
  bool has_size = false;   // w/h given (globally or per frame)
  double pose[3][4] = {};  // camera-to-world rows 0..2
  bool pose_ok = false;
  bool image_ok = false;
  int image_w = 0, image_h = 0;
};

std::string frame_name(const Frame& f) {
  return "frames[" + std::to_string(f.json_index) + "] (" + f.file_path + ")";
}

bool read_number(const json& j, const char* key, double& out) {
  if (!j.contains(key)) return false;
  const json& v = j[key];
  if (!v.is_number()) return false;
  out = v.get<double>();
  return true;
}

// Path comparison by components, as Python's PurePosixPath ordering (used by nerfstudio's
// argsort of the frame paths).
bool path_less(const std::string& a, const std::string& b) {
  const fs::path pa(a), pb(b);
  return std::lexicographical_compare(
      pa.begin(), pa.end(), pb.begin(), pb.end(),
      [](const fs::path& x, const fs::path& y) { return x.string() < y.string(); });
}

// Rotation taking unit vector a onto unit vector b (Rodrigues), with nerfstudio's handling of
// (anti)parallel vectors: a fixed perpendicular axis is used.
Mat3 rotation_between(std::array<double, 3> a, std::array<double, 3> b) {
  auto normalise = [](std::array<double, 3>& v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (double& x : v) x /= n;
  };
  auto cross = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return std::array<double, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                 u[0] * v[1] - u[1] * v[0]};
  };
  normalise(a);
  normalise(b);
  std::array<double, 3> v = cross(a, b);
  if (std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2]) < 1e-6) {
    const std::array<double, 3> x =
        std::abs(a[0]) < 1e-6 ? std::array<double, 3>{1, 0, 0} : std::array<double, 3>{0, 1, 0};
    v = cross(a, x);
  }
  normalise(v);
  const double c = std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0, 1.0);
  const double theta = std::acos(c);
  const Mat3 k = {{{0, -v[2], v[1]}, {v[2], 0, -v[0]}, {-v[1], v[0], 0}}};
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double kk = 0;
      for (int m = 0; m < 3; ++m) kk += k[i][m] * k[m][j];
      r[i][j] = (i == j ? 1.0 : 0.0) + std::sin(theta) * k[i][j] + (1 - std::cos(theta)) * kk;
    }
  return r;
}

// Checks the camera-to-world matrix of one frame and stores its top 3 rows.
void read_pose(const json& frame, Frame& f, ProblemList& problems, const std::string& file) {
  const std::string where = frame_name(f);
  if (!frame.contains("transform_matrix") || !frame["transform_matrix"].is_array()) {
    problems.error(file, where + ": has no transform_matrix",
                   "give each frame a 4x4 camera-to-world \"transform_matrix\"");
    return;
  }
  const json& m = frame["transform_matrix"];
  if (m.size() < 3 || m.size() > 4) {
    problems.error(file, where + ": transform_matrix must have 4 rows of 4 numbers",
                   "write the full 4x4 camera-to-world matrix");
    return;
  }
  for (int r = 0; r < 3; ++r) {
    if (!m[r].is_array() || m[r].size() != 4) {
      problems.error(file, where + ": transform_matrix must have 4 rows of 4 numbers",
                     "write the full 4x4 camera-to-world matrix");
      return;
    }
    for (int c = 0; c < 4; ++c) {
      // NaN / Infinity arrive here as null (read_json_lenient).
      if (!m[r][c].is_number()) {
        problems.error(file,
                       where + ": transform_matrix[" + std::to_string(r) + "][" +
                           std::to_string(c) + "] is NaN, infinite or not a number",
                       "fix or drop the frame (its pose is not valid)");
        return;
      }
      f.pose[r][c] = m[r][c].get<double>();
      if (!std::isfinite(f.pose[r][c])) {
        problems.error(file, where + ": transform_matrix has a NaN or infinite entry",
                       "fix or drop the frame (its pose is not valid)");
        return;
      }
    }
  }
  // A camera 1e300 away is damage, not a scene: it would set the auto-scale and squash every
  // other camera onto the origin.
  for (int r = 0; r < 3; ++r)
    if (!(std::abs(f.pose[r][3]) <= kMaxAbsTranslation)) {
      problems.error(file,
                     where + ": transform_matrix[" + std::to_string(r) +
                         "][3] is an implausible camera position (|t| > 10000)",
                     "fix or drop the frame (positions are in the scene's units, e.g. metres)");
      return;
    }
  // Rigid check: R^T R = I and det R = +1 (a camera matrix that scales, shears or mirrors would
  // give wrong rays silently).
  double worst = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double d = 0;
      for (int k = 0; k < 3; ++k) d += f.pose[k][i] * f.pose[k][j];
      worst = std::max(worst, std::abs(d - (i == j ? 1.0 : 0.0)));
    }
  const double(*p)[4] = f.pose;
  const double det = p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) -
                     p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                     p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0]);
  if (worst > 1e-3 || std::abs(det - 1) > 1e-3) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  ": the rotation part of transform_matrix is not a rotation (det %.4g, "
                  "max |RᵀR − I| %.2g)",
                  det, worst);
    problems.error(file, where + buf,
                   "write an orthonormal camera-to-world rotation with determinant +1");
    return;
  }
  f.pose_ok = true;
}

void check_intrinsics(Frame& f, ProblemList& problems, const std::string& file) {
  const Intrinsics& k = f.intr;
  const bool finite = std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) &&
                      std::isfinite(k.cy) && std::isfinite(k.k1) && std::isfinite(k.k2) &&
                      std::isfinite(k.k3) && std::isfinite(k.p1) && std::isfinite(k.p2);
  if (!finite || !(k.fx > 0) || !(k.fy > 0)) {
    problems.error(file, frame_name(f) + ": focal lengths must be positive finite numbers",
                   "set fl_x and fl_y (pixels) globally or per frame");
  }
}

// Python's json module writes NaN / Infinity / -Infinity for non-finite floats, which strict JSON
// parsers reject. Read them as null so the pose check can name the frame instead of failing on
// the whole file.
json read_json_lenient(const std::string& path) {
  std::string text = io::read_text_file(path);
  bool in_string = false, escaped = false;
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
      out += c;
      continue;
    }
    bool replaced = false;
    for (const char* word : {"-Infinity", "Infinity", "NaN"}) {
      const size_t n = std::strlen(word);
      if (text.compare(i, n, word) == 0) {
        out += "null";
        i += n - 1;
        replaced = true;
        break;
      }
    }
    if (!replaced) out += c;
  }
  return parse_json(out, path, "fix the file (it must be a nerfstudio transforms.json)");
}

struct Parsed {
  std::string json_path;
  std::string data_dir;
  json meta;
  std::vector<Frame> frames;  // sorted like nerfstudio
  std::string orientation;
};

Parsed parse(const std::string& path_in, const ImageLoadOptions& options, ProblemList& problems) {
  Parsed out;
  std::error_code ec;
  out.json_path =
      fs::is_directory(path_in, ec) ? (fs::path(path_in) / "transforms.json").string() : path_in;
  out.data_dir = fs::path(out.json_path).parent_path().string();
  if (out.data_dir.empty()) out.data_dir = ".";
  const std::string& file = out.json_path;
  if (!fs::exists(file, ec)) {
    problems.error(file, "no such file",
                   "point to a nerfstudio dataset folder holding transforms.json");
    return out;
  }
  try {
    out.meta = read_json_lenient(file);
  } catch (const Error& e) {
    problems.error("", e.what(), "");
    return out;
  }
  const json& meta = out.meta;
  if (!meta.is_object() || !meta.contains("frames") || !meta["frames"].is_array()) {
    problems.error(file, "has no \"frames\" list", "write a nerfstudio transforms.json");
    return out;
  }
  if (meta.contains("camera_model") && meta["camera_model"].is_string()) {
    const std::string model = meta["camera_model"];
    if (model != "OPENCV" && model != "PINHOLE" && model != "SIMPLE_PINHOLE" &&
        model != "perspective") {
      problems.error(file, "camera_model \"" + model + "\" is not supported",
                     "use OPENCV or PINHOLE cameras (undistort fisheye / equirectangular images "
                     "first)");
    }
  }

  out.orientation = options.orientation;
  if (out.orientation.empty()) {
    out.orientation = "up";
    if (meta.contains("orientation_override") && meta["orientation_override"].is_string())
      out.orientation = meta["orientation_override"].get<std::string>();
  }
  if (out.orientation != "up" && out.orientation != "none") {
    problems.error(file, "orientation \"" + out.orientation + "\" is not supported",
                   "use orientation_override \"up\" or \"none\"");
    out.orientation = "up";
  }

  const json& frames = meta["frames"];
  if (frames.empty()) {
    problems.error(file, "\"frames\" is empty", "list at least one posed image");
    return out;
  }
  // A value of the wrong type is reported as such (once for a global one), not as missing.
  for (const char* key : {"fl_x", "fl_y", "cx", "cy", "w", "h", "k1", "k2", "k3", "k4", "p1", "p2"})
    if (meta.contains(key) && !meta[key].is_number())
      problems.error(file,
                     std::string("\"") + key + "\" is not a number (" + meta[key].dump() + ")",
                     "write it as a number of pixels (or a coefficient) without quotes");
  for (size_t i = 0; i < frames.size(); ++i) {
    const json& fr = frames[i];
    Frame f;
    f.json_index = static_cast<int>(i);
    if (!fr.is_object() || !fr.contains("file_path") || !fr["file_path"].is_string()) {
      problems.error(file, "frames[" + std::to_string(i) + "]: has no file_path",
                     "give each frame a \"file_path\" relative to the transforms.json folder");
      continue;
    }
    f.file_path = fr["file_path"].get<std::string>();
    f.path = (fs::path(out.data_dir) / f.file_path).lexically_normal().string();

    // Per-frame values win only when the global one is absent (nerfstudio semantics).
    auto get = [&](const char* key, double& dst) {
      return read_number(meta, key, dst) || read_number(fr, key, dst);
    };
    bool ok = true;
    for (auto [key, dst] : {std::pair<const char*, double*>{"fl_x", &f.intr.fx},
                            {"fl_y", &f.intr.fy},
                            {"cx", &f.intr.cx},
                            {"cy", &f.intr.cy}}) {
      if (!get(key, *dst)) {
        if (fr.contains(key) && !meta.contains(key))
          problems.error(
              file, frame_name(f) + ": \"" + key + "\" is not a number (" + fr[key].dump() + ")",
              "write it as a number of pixels without quotes");
        else if (!meta.contains(key))
          problems.error(file, frame_name(f) + ": no " + key,
                         std::string("set \"") + key + "\" globally or in every frame");
        ok = false;
      }
    }
    double w = 0, h = 0;
    const bool has_w = get("w", w), has_h = get("h", h);
    f.has_size = has_w && has_h;
    f.intr.width = static_cast<int>(w);
    f.intr.height = static_cast<int>(h);
    // Distortion: nerfstudio treats the distortion as global if ANY coefficient is global.
    const bool distort_global = meta.contains("k1") || meta.contains("k2") || meta.contains("k3") ||
                                meta.contains("p1") || meta.contains("p2");
    const json& dsrc = distort_global ? meta : fr;
    read_number(dsrc, "k1", f.intr.k1);
    read_number(dsrc, "k2", f.intr.k2);
    read_number(dsrc, "k3", f.intr.k3);
    read_number(dsrc, "p1", f.intr.p1);
    read_number(dsrc, "p2", f.intr.p2);
    double k4 = 0;
    if (read_number(dsrc, "k4", k4) && k4 != 0)
      problems.error(file, frame_name(f) + ": k4 distortion is not supported",
                     "undistort the images or use the OPENCV model (k1, k2, k3, p1, p2)");
    if (ok) check_intrinsics(f, problems, file);
    read_pose(fr, f, problems, file);
    out.frames.push_back(std::move(f));
  }
  // The same image listed twice would be trained on twice as often (and counted twice in the
  // eval metrics); almost always a merge or copy-paste mistake.
  {
    std::map<std::string, int> first;
    std::vector<Frame> unique;
    for (Frame& f : out.frames) {
      const auto [it, fresh] = first.emplace(f.path, f.json_index);
      if (fresh) {
        unique.push_back(std::move(f));
        continue;
      }
      problems.error(file,
                     frame_name(f) + ": lists the same image as frames[" +
                         std::to_string(it->second) + "] (duplicate frame)",
                     "remove one of the two frames from transforms.json");
    }
    out.frames = std::move(unique);
  }
  // nerfstudio sorts the frames by file path before anything else (split indices depend on it).
  std::stable_sort(out.frames.begin(), out.frames.end(),
                   [](const Frame& a, const Frame& b) { return path_less(a.path, b.path); });
  return out;
}

// Reads each image's header; records sizes and problems.
void check_images(Parsed& p, ProblemList& problems) {
  for (Frame& f : p.frames) {
    std::error_code ec;
    if (!fs::exists(f.path, ec)) {
      problems.error(p.json_path, frame_name(f) + ": image " + f.path + " does not exist",
                     "add the image or remove the frame from transforms.json");
      continue;
    }
    // stb_image accepts a file cut short and decodes its missing part as zeros.
    const std::string damage = io::image_file_problem(f.path);
    if (!damage.empty()) {
      problems.error(p.json_path,
                     frame_name(f) + ": image " + f.path + " is unusable (" + damage + ")",
                     "re-copy or re-export the image");
      continue;
    }
    int w = 0, h = 0, n = 0;
    if (!stbi_info(f.path.c_str(), &w, &h, &n)) {
      problems.error(p.json_path,
                     frame_name(f) + ": image " + f.path + " cannot be read (" +
                         (stbi_failure_reason() ? stbi_failure_reason() : "unknown format") + ")",
                     "convert it to PNG or JPEG");
      continue;
    }
    f.image_w = w;
    f.image_h = h;
    if (f.has_size && (w != f.intr.width || h != f.intr.height)) {
      problems.error(p.json_path,
                     frame_name(f) + ": image is " + std::to_string(w) + "x" + std::to_string(h) +
                         " but the intrinsics say " + std::to_string(f.intr.width) + "x" +
                         std::to_string(f.intr.height),
                     "fix w/h (and fl_x, fl_y, cx, cy) or resize the image");
      continue;
    }
    if (!f.has_size) {  // take the size from the image itself
      f.intr.width = w;
      f.intr.height = h;
    }
    f.image_ok = true;
  }
}

bool contains(const std::string& s, const char* sub) { return s.find(sub) != std::string::npos; }

// Splits frame indices into train / eval following nerfstudio's rules.
void split_indices(const Parsed& p, const ImageLoadOptions& options, ProblemList& problems,
                   std::vector<int64_t>& train, std::vector<int64_t>& eval, std::string& mode) {
  const int64_t n = static_cast<int64_t>(p.frames.size());
  const json& meta = p.meta;
  if (meta.contains("train_filenames")) {
    mode = "lists";
    auto names = [&](const char* key) {
      std::vector<std::string> v;
      if (meta.contains(key) && meta[key].is_array())
        for (const json& x : meta[key])
          if (x.is_string())
            v.push_back((fs::path(p.data_dir) / x.get<std::string>()).lexically_normal().string());
      return v;
    };
    const auto tr = names("train_filenames");
    auto ev = names("val_filenames");
    if (ev.empty()) ev = names("test_filenames");
    for (int64_t i = 0; i < n; ++i) {
      if (std::find(tr.begin(), tr.end(), p.frames[i].path) != tr.end()) train.push_back(i);
      if (std::find(ev.begin(), ev.end(), p.frames[i].path) != ev.end()) eval.push_back(i);
    }
    for (const auto& list : {tr, ev})
      for (const std::string& name : list) {
        const bool found = std::any_of(p.frames.begin(), p.frames.end(),
                                       [&](const Frame& f) { return f.path == name; });
        if (!found)
          problems.error(p.json_path, "split list names " + name + ", which is not a frame",
                         "add the frame or remove the name from the list");
      }
    return;
  }
  std::string m = options.eval_mode;
  if (m == "auto") {
    const bool all_named = std::all_of(p.frames.begin(), p.frames.end(), [](const Frame& f) {
      const std::string base = fs::path(f.file_path).filename().string();
      return contains(base, "train_") || contains(base, "eval_");
    });
    m = all_named ? "filename" : "fraction";
  }
  mode = m;
  if (m == "filename") {
    for (int64_t i = 0; i < n; ++i) {
      const std::string base = fs::path(p.frames[i].file_path).filename().string();
      // nerfstudio checks "train" first, then "eval".
      if (contains(base, "train"))
        train.push_back(i);
      else if (contains(base, "eval"))
        eval.push_back(i);
      else
        problems.error(p.json_path,
                       frame_name(p.frames[i]) + ": file name has neither \"train\" nor \"eval\"",
                       "rename it (train_XXXX / eval_XXXX) or use the fraction split");
    }
  } else if (m == "fraction") {
    if (!(options.train_fraction > 0 && options.train_fraction <= 1))
      throw Error("train fraction " + std::to_string(options.train_fraction) +
                  " must be in (0, 1]");
    const int64_t n_train = static_cast<int64_t>(std::ceil(n * options.train_fraction));
    // numpy.linspace(0, n-1, n_train, dtype=int): evenly spaced values, truncated to integers.
    std::vector<char> is_train(n, 0);
    // Same arithmetic as numpy (k · step, then the endpoint set exactly) so that values that
    // land a rounding error below an integer truncate the same way.
    const double step = n_train > 1 ? double(n - 1) / double(n_train - 1) : 0.0;
    for (int64_t k = 0; k < n_train; ++k) {
      int64_t idx = static_cast<int64_t>(double(k) * step);
      if (k == n_train - 1 && n_train > 1) idx = n - 1;
      is_train[std::clamp<int64_t>(idx, 0, n - 1)] = 1;
    }
    for (int64_t i = 0; i < n; ++i) (is_train[i] ? train : eval).push_back(i);
  } else {
    throw Error("eval mode \"" + m + "\" is not known; use auto, filename or fraction");
  }
}

// Decodes every image that passed the header checks (in parallel, one image per thread in memory
// at a time), so that validation finds what the pixel loader would throw on.
void check_decodes(const Parsed& p, ProblemList& problems) {
  const int64_t n = static_cast<int64_t>(p.frames.size());
  std::vector<std::string> failures(static_cast<size_t>(n));
#pragma omp parallel for schedule(dynamic)
  for (int64_t k = 0; k < n; ++k) {
    const Frame& f = p.frames[k];
    if (!f.image_ok) continue;
    int w = 0, h = 0, c = 0;
    stbi_uc* px = stbi_load(f.path.c_str(), &w, &h, &c, 3);
    if (!px || w != f.image_w || h != f.image_h)
      failures[k] = frame_name(f) + ": image " + f.path + " cannot be decoded (" +
                    (px ? "its size changed" : "damaged image data") + ")";
    if (px) stbi_image_free(px);
  }
  for (const std::string& msg : failures)
    if (!msg.empty()) problems.error(p.json_path, msg, "re-export the image as PNG or JPEG");
}

ImageSet build(const std::string& path, const ImageLoadOptions& options, ProblemList& problems,
               bool decode, bool verify_pixels = false) {
  Parsed p = parse(path, options, problems);
  ImageSet set;
  set.source = p.json_path;
  set.world_transform = torch::zeros({3, 4}, torch::kFloat64);
  for (int i = 0; i < 3; ++i) set.world_transform[i][i] = 1.0;
  if (p.frames.empty()) return set;
  check_images(p, problems);

  std::vector<int64_t> train, eval;
  split_indices(p, options, problems, train, eval, set.eval_mode);
  if (train.empty())
    problems.error(p.json_path, "the train split is empty (eval mode " + set.eval_mode + ")",
                   "add train frames (file names with train_ for the filename split)");
  if (eval.empty())
    problems.warning(p.json_path, "the eval split is empty (eval mode " + set.eval_mode + ")",
                     "image metrics will be skipped; add eval_ frames or more images");

  // Frame size consistency (the images tensor is [N, H, W, 3]).
  const Frame* first = nullptr;
  for (const Frame& f : p.frames) {
    if (!f.image_ok) continue;
    if (!first) {
      first = &f;
    } else if (f.image_w != first->image_w || f.image_h != first->image_h) {
      problems.error(p.json_path,
                     frame_name(f) + ": image is " + std::to_string(f.image_w) + "x" +
                         std::to_string(f.image_h) + " but " + frame_name(*first) + " is " +
                         std::to_string(first->image_w) + "x" + std::to_string(first->image_h),
                     "all images of a scene must have the same size; resize them");
    }
  }

  // Pose normalisation over all frames with a valid pose, before the split (as nerfstudio).
  std::vector<const Frame*> posed;
  for (const Frame& f : p.frames)
    if (f.pose_ok) posed.push_back(&f);
  Mat3 rot = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  std::array<double, 3> mean{0, 0, 0};
  if (!posed.empty()) {
    std::array<double, 3> up{0, 0, 0};
    for (const Frame* f : posed)
      for (int r = 0; r < 3; ++r) {
        mean[r] += f->pose[r][3] / posed.size();
        up[r] += f->pose[r][1] / posed.size();  // camera y axis = "up" in OpenGL cameras
      }
    if (p.orientation == "up") {
      const double un = std::sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
      if (un > 1e-12) {
        rot = rotation_between(up, {0, 0, 1});
      } else {
        problems.warning(p.json_path, "the cameras' up vectors cancel out; orientation skipped",
                         "set \"orientation_override\": \"none\" to silence this");
      }
    }
  }
  std::array<double, 3> t{};
  for (int r = 0; r < 3; ++r)
    t[r] = -(rot[r][0] * mean[0] + rot[r][1] * mean[1] + rot[r][2] * mean[2]);
  // Oriented poses: [rot·Rc | rot·tc + t].
  std::vector<std::array<double, 12>> oriented(p.frames.size());
  double max_abs_t = 0;
  for (size_t i = 0; i < p.frames.size(); ++i) {
    const Frame& f = p.frames[i];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        double v = 0;
        for (int k = 0; k < 3; ++k) v += rot[r][k] * f.pose[k][c];
        if (c == 3) v += t[r];
        oriented[i][r * 4 + c] = v;
      }
    if (f.pose_ok)
      for (int r = 0; r < 3; ++r) max_abs_t = std::max(max_abs_t, std::abs(oriented[i][r * 4 + 3]));
  }
  double scale = 1.0;
  if (options.auto_scale) {
    if (max_abs_t > 0) {
      scale = 1.0 / max_abs_t;
    } else if (posed.size() > 1) {
      problems.warning(p.json_path, "all cameras are at the same position; scale left at 1",
                       "check the transform_matrix translations");
    }
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) set.world_transform[r][c] = rot[r][c];
    set.world_transform[r][3] = t[r];
  }
  set.world_scale = scale;

  auto fill = [&](ImageSplit& split, const std::vector<int64_t>& idx, bool is_train) {
    const int64_t n = static_cast<int64_t>(idx.size());
    split.camera_to_world = torch::zeros({n, 3, 4}, torch::kFloat32);
    auto acc = split.camera_to_world.accessor<float, 3>();
    for (int64_t k = 0; k < n; ++k) {
      const Frame& f = p.frames[idx[k]];
      split.files.push_back(f.path);
      split.intrinsics.push_back(f.intr);
      split.appearance_ids.push_back(is_train ? k : -1);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c)
          acc[k][r][c] = static_cast<float>(oriented[idx[k]][r * 4 + c] * (c == 3 ? scale : 1.0));
    }
  };
  fill(set.train, train, true);
  fill(set.eval, eval, false);

  if (!decode) {
    if (verify_pixels) check_decodes(p, problems);
    return set;
  }
  if (problems.num_errors() > 0 || !first) return set;

  const int H = first->image_h, W = first->image_w;
  ProgressOptions popt;
  popt.unit = "img";
  popt.enabled = options.progress;
  Progress progress("loading images", static_cast<int64_t>(p.frames.size()), popt);
  std::atomic<int64_t> done{0};
  for (ImageSplit* split : {&set.train, &set.eval}) {
    const int64_t n = split->size();
    split->images = torch::empty({n, H, W, 3}, torch::kUInt8);
    uint8_t* base = split->images.data_ptr<uint8_t>();
    std::vector<std::string> failures(n);
#pragma omp parallel for schedule(dynamic)
    for (int64_t k = 0; k < n; ++k) {
      int w = 0, h = 0, c = 0;
      stbi_uc* px = stbi_load(split->files[k].c_str(), &w, &h, &c, 3);
      if (!px || w != W || h != H) {
        failures[k] = split->files[k] + ": cannot be decoded (" +
                      (stbi_failure_reason() ? stbi_failure_reason() : "size changed") +
                      "); re-export the image as PNG or JPEG";
      } else {
        std::memcpy(base + k * int64_t(H) * W * 3, px, size_t(H) * W * 3);
      }
      if (px) stbi_image_free(px);
      const int64_t d = ++done;
      if (omp_get_thread_num() == 0) progress.update(d);  // Progress is not thread-safe
    }
    for (const std::string& msg : failures)
      if (!msg.empty()) throw Error(msg);
  }
  progress.finish();
  return set;
}

}  // namespace

ImageSet check_transforms_json(const std::string& path, const ImageLoadOptions& options,
                               ProblemList& problems) {
  return build(path, options, problems, /*decode=*/false, /*verify_pixels=*/true);
}

ImageSet load_transforms_json(const std::string& path, const ImageLoadOptions& options) {
  ProblemList problems;
  ImageSet set = build(path, options, problems, options.load_pixels);
  problems.throw_if_errors(fs::path(set.source).parent_path().string());
  problems.print_warnings();
  return set;
}

torch::Tensor to_normalized_world(const ImageSet& set, const torch::Tensor& points) {
  TORCH_CHECK(points.dim() == 2 && points.size(1) == 3, "points must be [N, 3]");
  const torch::Tensor p = points.to(torch::kFloat64);
  const torch::Tensor r =
      set.world_transform.index({torch::indexing::Slice(), torch::indexing::Slice(0, 3)});
  const torch::Tensor t = set.world_transform.index({torch::indexing::Slice(), 3});
  return (p.matmul(r.t()) + t) * set.world_scale;
}

}  // namespace neraf::data
