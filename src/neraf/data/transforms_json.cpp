#include "neraf/data/transforms_json.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <tuple>

#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data::detail {
namespace {

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

// Checks the camera-to-world matrix of one frame and stores its top 3 rows.
void read_pose(const json& frame, TransformsFrame& f, ProblemList& problems,
               const std::string& file) {
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
      // NaN / Infinity arrive here as null (parse_json_lenient).
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

void check_intrinsics(TransformsFrame& f, ProblemList& problems, const std::string& file) {
  const Intrinsics& k = f.intr;
  if (!std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    problems.error(file, frame_name(f) + ": cx and cy must be finite numbers",
                   "set cx and cy (pixels) globally or per frame");
    return;
  }
  const std::string problem = intrinsics_problem(k, "fl_x", "fl_y");
  if (!problem.empty())
    problems.error(file, frame_name(f) + ": " + problem,
                   "set fl_x and fl_y (pixels) and the distortion coefficients globally or per "
                   "frame to the camera's calibration");
}

// Python's json module writes NaN / Infinity / -Infinity for non-finite floats, which strict JSON
// parsers reject. Read them as null so the pose check can name the frame instead of failing on
// the whole file.
json parse_json_lenient(const std::string& text, const std::string& path) {
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

// An image side as w / h give it: whole pixels (12.5 is no size, and 1e300 does not fit an int).
bool whole_pixels(double v) { return v >= 1 && v <= kMaxImageSide && v == std::floor(v); }

bool contains(const std::string& s, const char* sub) { return s.find(sub) != std::string::npos; }

bool has_control_character(const std::string& s) {
  return std::any_of(s.begin(), s.end(),
                     [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
}

}  // namespace

std::string frame_name(const TransformsFrame& f) {
  // A path that is long or holds a control character is quoted (and cut) by json_quoted, so the
  // one-line messages stay one short line; the usual path reads as it is written.
  const bool plain = f.file_path.size() <= kQuotedMaxBytes && !has_control_character(f.file_path);
  return "frames[" + std::to_string(f.json_index) + "] (" +
         (plain ? f.file_path : json_quoted(f.file_path)) + ")";
}

Transforms parse_transforms_json(const std::string& text, const std::string& json_path,
                                 const std::string& data_dir, const std::string& orientation,
                                 ProblemList& problems) {
  Transforms out;
  out.json_path = json_path;
  out.data_dir = data_dir;
  const std::string& file = out.json_path;
  try {
    out.meta = parse_json_lenient(text, file);
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

  out.orientation = orientation;
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
  for (const char* key : {"w", "h"})
    if (meta.contains(key) && meta[key].is_number() && !whole_pixels(meta[key].get<double>()))
      problems.error(file,
                     std::string("\"") + key + "\" is not a whole number of pixels in 1.." +
                         std::to_string(kMaxImageSide) + " (" + meta[key].dump() + ")",
                     "write the image's width and height in pixels");
  for (size_t i = 0; i < frames.size(); ++i) {
    const json& fr = frames[i];
    TransformsFrame f;
    f.json_index = static_cast<int>(i);
    if (!fr.is_object() || !fr.contains("file_path") || !fr["file_path"].is_string()) {
      problems.error(file, "frames[" + std::to_string(i) + "]: has no file_path",
                     "give each frame a \"file_path\" relative to the transforms.json folder");
      continue;
    }
    f.file_path = fr["file_path"].get<std::string>();
    // A NUL would end the path early (the file before it would be read), a newline split messages.
    if (has_control_character(f.file_path)) {
      problems.error(file,
                     "frames[" + std::to_string(i) + "]: file_path " + json_quoted(f.file_path) +
                         " holds a control character",
                     "write the image's path relative to the transforms.json folder");
      continue;
    }
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
    bool size_ok = true;
    for (auto [key, v, has] :
         {std::tuple<const char*, double, bool>{"w", w, has_w}, {"h", h, has_h}}) {
      if (!has || whole_pixels(v)) continue;
      size_ok = false;
      if (!meta.contains(key))  // a bad global size was reported once, above
        problems.error(file,
                       frame_name(f) + ": \"" + key + "\" is not a whole number of pixels in 1.." +
                           std::to_string(kMaxImageSide) + " (" + fr[key].dump() + ")",
                       "write the image's width and height in pixels");
    }
    f.has_size = has_w && has_h && size_ok;
    if (f.has_size) {
      f.intr.width = static_cast<int>(w);
      f.intr.height = static_cast<int>(h);
    }
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
    std::vector<TransformsFrame> unique;
    for (TransformsFrame& f : out.frames) {
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
  std::stable_sort(
      out.frames.begin(), out.frames.end(),
      [](const TransformsFrame& a, const TransformsFrame& b) { return path_less(a.path, b.path); });
  return out;
}

void split_transforms(const Transforms& p, const std::string& eval_mode, double train_fraction,
                      ProblemList& problems, std::vector<int64_t>& train,
                      std::vector<int64_t>& eval, std::string& mode) {
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
                                       [&](const TransformsFrame& f) { return f.path == name; });
        if (!found)
          problems.error(p.json_path, "split list names " + name + ", which is not a frame",
                         "add the frame or remove the name from the list");
      }
    return;
  }
  std::string m = eval_mode;
  if (m == "auto") {
    const bool all_named =
        std::all_of(p.frames.begin(), p.frames.end(), [](const TransformsFrame& f) {
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
    if (!(train_fraction > 0 && train_fraction <= 1))
      throw Error("train fraction " + std::to_string(train_fraction) + " must be in (0, 1]");
    const int64_t n_train = static_cast<int64_t>(std::ceil(n * train_fraction));
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

}  // namespace neraf::data::detail

namespace neraf::data {

std::string intrinsics_problem(const Intrinsics& k, const char* fx_key, const char* fy_key) {
  auto number = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return std::string(buf);
  };
  for (auto [key, v] : {std::pair<const char*, double>{fx_key, k.fx}, {fy_key, k.fy}})
    if (!(v >= kMinFocalPixels && v <= kMaxFocalPixels))
      return std::string(key) + " is " + number(v) + ", outside " + number(kMinFocalPixels) + ".." +
             number(kMaxFocalPixels) + " pixels";
  for (auto [key, v] : {std::pair<const char*, double>{"k1", k.k1},
                        {"k2", k.k2},
                        {"k3", k.k3},
                        {"p1", k.p1},
                        {"p2", k.p2}})
    if (!(std::abs(v) <= kMaxAbsDistortion))
      return std::string("distortion ") + key + " is " + number(v) + ", outside ±" +
             number(kMaxAbsDistortion);
  return "";
}

}  // namespace neraf::data
