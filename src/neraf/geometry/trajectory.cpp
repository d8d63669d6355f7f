#include "neraf/geometry/trajectory.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace neraf::geometry {

using nlohmann::json;

namespace {

// Larger files are certainly not paths: 100000 poses take about 10 MB.
constexpr uintmax_t kMaxFileBytes = 64u << 20;

constexpr const char* kPositionWhat = "[x, y, z]: three numbers in metres";

std::string fmt(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string index(const std::string& path, size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

[[noreturn]] void fail(const std::string& where, const std::string& path,
                       const std::string& message) {
  throw Error(where + ": " + (path.empty() ? "" : path + ": ") + message);
}

// Unknown keys are errors, so that a typo ("yaww") is not silently ignored.
void check_object(const std::string& where, const json& j, const std::string& path,
                  std::initializer_list<const char*> known) {
  if (!j.is_object()) {
    fail(where, path, path.empty() ? "must be a JSON object {...}" : "must be an object {...}");
  }
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return it.key() == k; })) {
      std::string names;
      for (const char* k : known) names += (names.empty() ? "" : ", ") + std::string(k);
      fail(where, path,
           "unknown key " + json_quoted(it.key()) + " (known keys: " + names +
               "); fix the spelling or remove it");
    }
  }
}

const json* find(const json& j, const char* key) {
  auto it = j.find(key);
  return it == j.end() ? nullptr : &*it;
}

// "version" is required: a file without it may be meant for another program.
void check_version(const std::string& where, const json& j) {
  const json* v = find(j, "version");
  if (!v) fail(where, "", "missing \"version\"; add \"version\": 1 (the format version)");
  const std::string fix = "must be " + std::to_string(kPathFormatVersion) + " (the format version)";
  if (!v->is_number()) fail(where, "version", fix);
  const double n = v->get<double>();
  if (std::isfinite(n) && n == std::floor(n) && n > kPathFormatVersion) {
    fail(where, "version",
         fmt(n) + ": written for a newer neraf (this one reads version " +
             std::to_string(kPathFormatVersion) + "); update neraf");
  }
  if (n != kPathFormatVersion) fail(where, "version", fmt(n) + " " + fix);
}

void check_description(const std::string& where, const json& j) {
  const json* d = find(j, "description");
  if (d && !d->is_string()) fail(where, "description", "must be a string (free text)");
}

Vec3 read_position(const std::string& where, const json& j, const std::string& path) {
  if (!j.is_array() || j.size() != 3) fail(where, path, std::string("must be ") + kPositionWhat);
  Vec3 p;
  for (int a = 0; a < 3; ++a) {
    const json& c = j[a];
    if (!c.is_number()) fail(where, path, std::string("must be ") + kPositionWhat);
    p[a] = c.get<double>();
    if (!std::isfinite(p[a])) {
      fail(where, path, std::string("must be ") + kPositionWhat + " (finite, not NaN or inf)");
    }
    if (std::abs(p[a]) > kMaxAbsCoordinateM) {
      fail(where, path,
           "coordinate " + fmt(p[a]) + " is beyond ±" + fmt(kMaxAbsCoordinateM) +
               " m; positions are metres in the dataset's frame (not millimetres)");
    }
  }
  return p;
}

// The angle in [0, 360). fmod keeps whole turns exact; a tiny negative angle can round up to 360.
double wrap_deg(double deg) {
  double r = std::fmod(deg, 360.0);
  if (r < 0) r += 360.0;
  return r >= 360.0 ? 0.0 : r;
}

double read_yaw(const std::string& where, const json& j, const std::string& path) {
  const std::string what = "must be a number of degrees (a heading)";
  if (!j.is_number()) fail(where, path, what);
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(where, path, what + ", finite");
  if (std::abs(v) > kMaxAbsYawDeg) {
    fail(where, path,
         fmt(v) + " is beyond ±" + fmt(kMaxAbsYawDeg) + " degrees; write the angle modulo 360");
  }
  return wrap_deg(v);
}

double read_time(const std::string& where, const json& j, const std::string& path) {
  const std::string what =
      "must be a number of seconds from the start, in [0, " + fmt(kMaxTimeS) + "]";
  if (!j.is_number()) fail(where, path, what);
  const double t = j.get<double>();
  if (!std::isfinite(t) || t < 0 || t > kMaxTimeS) fail(where, path, fmt(t) + " " + what);
  return t;
}

// The element `key` of object `j`, or an error saying how to add it.
const json& required(const std::string& where, const json& j, const std::string& path,
                     const char* key, const std::string& what) {
  const json* v = find(j, key);
  if (!v) fail(where, path, "missing \"" + std::string(key) + "\"; add it (" + what + ")");
  return *v;
}

// The array `key` of the top-level object, with between 1 and `max` elements; checked before
// anything is allocated for it.
const json& read_list(const std::string& where, const json& j, const char* key, size_t max,
                      const std::string& element) {
  const json& list = required(where, j, "", key, "a list of " + element + " objects");
  if (!list.is_array()) fail(where, key, "must be a list [...] of " + element + " objects");
  if (list.empty()) fail(where, key, "is empty; add at least one " + element);
  if (list.size() > max) {
    fail(where, key,
         std::to_string(list.size()) + " entries, more than the " + std::to_string(max) +
             " allowed; split the file");
  }
  return list;
}

Trajectory parse_trajectory_unchecked(const json& j, const std::string& where) {
  // The two formats of docs/PATH_FORMAT.md are easily swapped: say which command takes the other.
  if (j.is_object() && j.contains("poses") && !j.contains("keyframes"))
    fail(where, "",
         "is a pose list (\"poses\"), not a timed path (\"keyframes\"); render it with "
         "neraf render rir --poses");
  check_object(where, j, "", {"version", "description", "source", "keyframes"});
  check_version(where, j);
  check_description(where, j);
  const json* fixed_source = find(j, "source");
  const json& list = read_list(where, j, "keyframes", kMaxKeyframes, "keyframe");

  Trajectory tr;
  // keyframes[0] decides: with a "source" every keyframe needs one. (When it is not an object the
  // loop below says so.)
  const bool first_has_source = list[0].is_object() && list[0].contains("source");
  if (!fixed_source && !first_has_source && list[0].is_object()) {
    fail(where, "",
         "no source position: add a top-level \"source\": [x, y, z] (a fixed source) or a "
         "\"source\" to every keyframe (a moving one)");
  }
  tr.moving_source = fixed_source == nullptr;
  const Vec3 fixed = fixed_source ? read_position(where, *fixed_source, "source") : Vec3{};

  tr.keyframes.reserve(list.size());
  for (size_t i = 0; i < list.size(); ++i) {
    const json& k = list[i];
    const std::string path = index("keyframes", i);
    check_object(where, k, path, {"time", "mic", "yaw", "source"});
    TimedPose p;
    p.time = read_time(where, required(where, k, path, "time", "seconds from the start"),
                       path + ".time");
    if (i > 0 && !(p.time > tr.keyframes.back().time)) {
      fail(where, path + ".time",
           fmt(p.time) + " is not after " + index("keyframes", i - 1) + ".time (" +
               fmt(tr.keyframes.back().time) +
               "); keyframe times must strictly increase (sort the keyframes or fix the time)");
    }
    p.mic = read_position(where, required(where, k, path, "mic", kPositionWhat), path + ".mic");
    p.yaw_deg = read_yaw(where, required(where, k, path, "yaw", "degrees"), path + ".yaw");
    const json* s = find(k, "source");
    if (fixed_source && s) {
      fail(where, path + ".source",
           "the file also has a top-level \"source\"; keep one: the top-level one for a fixed "
           "source, or one per keyframe for a moving one");
    }
    if (tr.moving_source && !s) {
      fail(where, path,
           "missing \"source\": keyframes[0] has one, so every keyframe needs one (or give a "
           "single top-level \"source\" instead)");
    }
    p.source = s ? read_position(where, *s, path + ".source") : fixed;
    tr.keyframes.push_back(p);
  }
  return tr;
}

bool safe_name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
         c == '_' || c == '.';
}

std::string lower(std::string s) {
  for (char& c : s) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return s;
}

std::string read_name(const std::string& where, const json& j, const std::string& path) {
  const std::string rule =
      "letters, digits, '-', '_' and '.' only, not starting with '.' nor holding \".tmp-\", at "
      "most " +
      std::to_string(kMaxPoseNameLength) + " characters";
  if (!j.is_string()) fail(where, path, "must be a string (" + rule + ")");
  const std::string name = j.get<std::string>();
  // ".tmp-" marks the files neraf is writing (io/atomic_file.h): never a pose's own.
  const bool ok = !name.empty() && name.size() <= kMaxPoseNameLength && name[0] != '.' &&
                  std::all_of(name.begin(), name.end(), safe_name_char) &&
                  name.find(".tmp-") == std::string::npos;
  // The name becomes a file name: anything else could leave the output folder ("../x") or trip
  // up shells.
  if (!ok) fail(where, path, json_quoted(name) + " is not a safe file name; use " + rule);
  return name;
}

std::vector<NamedPose> parse_pose_list_unchecked(const json& j, const std::string& where) {
  if (j.is_object() && j.contains("keyframes") && !j.contains("poses"))
    fail(where, "",
         "is a timed path (\"keyframes\"), not a pose list (\"poses\"); render it with "
         "neraf render trajectory --path");
  check_object(where, j, "", {"version", "description", "source", "poses"});
  check_version(where, j);
  check_description(where, j);
  const json* fixed_source = find(j, "source");
  const Vec3 fixed = fixed_source ? read_position(where, *fixed_source, "source") : Vec3{};
  const json& list = read_list(where, j, "poses", kMaxPoses, "pose");

  std::vector<NamedPose> poses;
  poses.reserve(list.size());
  // Lower-cased names → pose index: names are compared ignoring case, since "A.wav" and "a.wav"
  // are one file on case-insensitive file systems.
  std::map<std::string, size_t> taken;
  for (size_t i = 0; i < list.size(); ++i) {
    const json& k = list[i];
    const std::string path = index("poses", i);
    check_object(where, k, path, {"name", "mic", "source", "yaw"});
    NamedPose p;
    const json* n = find(k, "name");
    p.name = n ? read_name(where, *n, path + ".name") : default_pose_name(i);
    const auto [it, inserted] = taken.emplace(lower(p.name), i);
    if (!inserted) {
      fail(where, n ? path + ".name" : path,
           std::string(n ? "" : "its default name ") + "\"" + p.name +
               "\" is already the name of " + index("poses", it->second) +
               " (names become file names, so they must be unique, ignoring case); rename one");
    }
    p.mic = read_position(where, required(where, k, path, "mic", kPositionWhat), path + ".mic");
    const json* s = find(k, "source");
    if (!s && !fixed_source) {
      fail(where, path,
           "missing \"source\"; add it (" + std::string(kPositionWhat) +
               ") or one top-level \"source\" for every pose without one");
    }
    // A pose's own source wins over the top-level one.
    p.source = s ? read_position(where, *s, path + ".source") : fixed;
    p.yaw_deg = read_yaw(where, required(where, k, path, "yaw", "degrees"), path + ".yaw");
    poses.push_back(std::move(p));
  }
  return poses;
}

json read_json_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  require(fs::exists(path, ec), path + ": no such file; check the path");
  require(!fs::is_directory(path, ec), path + ": is a folder, expected a JSON file");
  // A FIFO or device would block the read (or never end).
  require(fs::is_regular_file(path, ec), path + ": is not a regular file; expected a JSON file");
  const uintmax_t size = fs::file_size(path, ec);
  require(ec || size <= kMaxFileBytes, path + ": " + std::to_string(size) +
                                           " bytes, too large for a path or pose list (at most " +
                                           std::to_string(kMaxFileBytes >> 20) + " MiB); split it");
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path + ": cannot open (" + std::strerror(errno) + "); check its permissions");
  std::ostringstream text;
  text << in.rdbuf();
  require(!in.bad(), path + ": read failed; check the file");
  return parse_json(text.str(), path, "fix the file (docs/PATH_FORMAT.md)");
}

}  // namespace

double Trajectory::duration() const { return keyframes.empty() ? 0.0 : keyframes.back().time; }

TimedPose Trajectory::at(double t) const {
  require(!keyframes.empty(), "trajectory has no keyframes");
  TimedPose p;
  if (!(t > keyframes.front().time)) {  // also NaN
    p = keyframes.front();
  } else if (t >= keyframes.back().time) {
    p = keyframes.back();
  } else {
    // The segment [a, b] with a.time <= t < b.time.
    const auto next = std::upper_bound(keyframes.begin(), keyframes.end(), t,
                                       [](double v, const TimedPose& k) { return v < k.time; });
    const TimedPose& a = *(next - 1);
    const TimedPose& b = *next;
    const double f = (t - a.time) / (b.time - a.time);
    p.mic = a.mic + f * (b.mic - a.mic);
    p.source = a.source + f * (b.source - a.source);
    // Both yaws are in [0, 360), so the difference is in (-360, 360); bring it to (-180, 180].
    double d = b.yaw_deg - a.yaw_deg;
    if (d > 180.0) d -= 360.0;
    if (d <= -180.0) d += 360.0;
    p.yaw_deg = wrap_deg(a.yaw_deg + f * d);
  }
  p.time = t;
  return p;
}

std::vector<TimedPose> sample_trajectory(const Trajectory& trajectory, double rate_hz,
                                         double duration_s) {
  require(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= kMaxSampleRateHz,
          "trajectory sample rate " + fmt(rate_hz) + " Hz: must be more than 0 and at most " +
              fmt(kMaxSampleRateHz) + " Hz (poses per second)");
  require(std::isfinite(duration_s) && duration_s > 0,
          "trajectory duration " + fmt(duration_s) + " s: must be a positive number of seconds");
  const double count = duration_s * rate_hz;
  require(count <= static_cast<double>(kMaxTrajectorySamples),
          "trajectory of " + fmt(duration_s) + " s at " + fmt(rate_hz) + " Hz is " + fmt(count) +
              " poses, more than the " + std::to_string(kMaxTrajectorySamples) +
              " allowed; lower the rate or the duration");
  require(!trajectory.keyframes.empty(), "trajectory has no keyframes");
  std::vector<TimedPose> out;
  out.reserve(static_cast<size_t>(std::ceil(count)) + 1);
  // t = k / rate, not a running sum, so that the times do not drift.
  for (size_t k = 0;; ++k) {
    const double t = static_cast<double>(k) / rate_hz;
    if (!(t < duration_s)) break;
    out.push_back(trajectory.at(t));
  }
  return out;
}

Trajectory parse_trajectory(const json& j, const std::string& where) {
  try {
    return parse_trajectory_unchecked(j, where);
  } catch (const json::exception& e) {  // not expected (types are checked first); never crash
    throw Error(where + ": unexpected JSON content (" + e.what() + "); see docs/PATH_FORMAT.md");
  }
}

Trajectory load_trajectory(const std::string& path) {
  return parse_trajectory(read_json_file(path), path);
}

std::string default_pose_name(size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "pose_%04zu", index);
  return buf;
}

std::vector<NamedPose> parse_pose_list(const json& j, const std::string& where) {
  try {
    return parse_pose_list_unchecked(j, where);
  } catch (const json::exception& e) {  // not expected (types are checked first); never crash
    throw Error(where + ": unexpected JSON content (" + e.what() + "); see docs/PATH_FORMAT.md");
  }
}

std::vector<NamedPose> load_pose_list(const std::string& path) {
  return parse_pose_list(read_json_file(path), path);
}

}  // namespace neraf::geometry
