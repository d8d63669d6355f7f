#include "neraf/data/pose_files.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "neraf/geometry/quaternion.h"
#include "neraf/util/json_text.h"

using nlohmann::json;

namespace neraf::data::detail {
namespace {

// "|v| ≤ kMaxAbsPoseCoordinate and finite" for every value (1e300 is a typo or damage, and it
// would silently zero every normalised position or overflow to infinity).
bool plausible(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!(std::abs(v[i]) <= kMaxAbsPoseCoordinate)) return false;
  return true;
}

// The whole token is a number (strtol/strtod stop at a NUL byte or at trailing text).
bool to_long(const std::string& t, long& v) {
  if (t.empty()) return false;
  char* end = nullptr;
  errno = 0;
  v = std::strtol(t.c_str(), &end, 10);
  return errno == 0 && end == t.c_str() + t.size();
}
bool to_double(const std::string& t, double& v) {
  char* end = nullptr;
  v = std::strtod(t.c_str(), &end);
  return !t.empty() && end == t.c_str() + t.size();
}

// "<rot>/<r>_<s>" written as its three whole numbers print ("270/122_44", not "270/0122_44" or
// "+270/122_44"): the wav's name is built from the numbers, so two spellings would be two entries
// of one file. False when malformed.
bool parse_entry(const std::string& e, int& rot, long& r, long& s) {
  const size_t slash = e.find('/');
  if (slash == std::string::npos) return false;
  const size_t under = e.find('_', slash + 1);
  if (under == std::string::npos) return false;
  long rl = 0;
  if (!to_long(e.substr(0, slash), rl) || !to_long(e.substr(slash + 1, under - slash - 1), r) ||
      !to_long(e.substr(under + 1), s) || rl < INT_MIN || rl > INT_MAX)
    return false;
  rot = static_cast<int>(rl);
  return e == std::to_string(rot) + "/" + std::to_string(r) + "_" + std::to_string(s);
}

// The numbers of a one-line text file separated by commas and/or white space. False if a token
// is not a number. Stops after `max_count` + 1 numbers (the count is wrong then anyway).
bool read_numbers(const std::string& text, size_t max_count, std::vector<double>& out) {
  std::string t = text;
  std::replace(t.begin(), t.end(), ',', ' ');
  std::istringstream is(t);
  std::string tok;
  out.clear();
  while (out.size() <= max_count && is >> tok) {
    double v = 0;
    if (!to_double(tok, v)) return false;
    out.push_back(v);
  }
  return true;
}

}  // namespace

std::optional<std::string> read_file_text(const std::string& path) {
  // A FIFO or a device would block the read or never end: only regular files (symlinks followed).
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in.good()) return std::nullopt;
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// ---- SoundSpaces ------------------------------------------------------------------------------

std::map<long, geometry::Vec3> parse_points_txt(const std::string& text, const std::string& path,
                                                ProblemList& problems) {
  std::map<long, geometry::Vec3> points;
  std::istringstream in(text);
  std::string line;
  int64_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = "line " + std::to_string(line_no);
    std::istringstream ls(line);
    std::string tok[4], extra;
    int n = 0;
    while (n < 4 && ls >> tok[n]) ++n;
    if (n == 4 && ls >> extra) {
      problems.error(path,
                     where + ": more than 4 columns; expected 'idx<TAB>x<TAB>y<TAB>z', got " +
                         json_quoted(line),
                     "remove the extra columns");
      continue;
    }
    long id = 0;
    double v[3];
    bool ok = n == 4;
    for (int k = 0; k < 3 && ok; ++k) ok = to_double(tok[k + 1], v[k]);
    if (ok) {
      char* end = nullptr;
      errno = 0;
      id = std::strtol(tok[0].c_str(), &end, 10);
      ok = end == tok[0].c_str() + tok[0].size();
      if (ok && errno == ERANGE) {  // strtol clamps it to LONG_MAX / LONG_MIN
        problems.error(path, where + ": point index " + json_quoted(tok[0]) + " is out of range",
                       "number the points 0, 1, 2, ... as the SoundSpaces release does");
        continue;
      }
    }
    if (!ok) {
      problems.error(path, where + ": expected 'idx<TAB>x<TAB>y<TAB>z', got " + json_quoted(line),
                     "fix the line");
      continue;
    }
    if (!plausible(v, 3)) {
      problems.error(path,
                     where + ": point " + std::to_string(id) +
                         " has a NaN, infinite or implausible coordinate (|x| > 10000 m)",
                     "fix the coordinates (metres) or remove the point and the RIRs that use it");
      continue;
    }
    if (points.count(id)) {
      problems.error(path, where + ": duplicate point index " + std::to_string(id),
                     "give every point a unique index");
      continue;
    }
    points[id] = {v[0], v[2], -v[1]};  // Habitat y-up → the frame NeRAF uses (no height offset)
  }
  return points;
}

bool parse_soundspaces_split(const json& split, const std::string& split_path,
                             const std::map<long, geometry::Vec3>& points, ProblemList& problems,
                             const std::function<void(const SoundSpacesEntry&)>& use) {
  if (!split.is_object() || !split.contains("train") || !split.at("train").is_array() ||
      !split.contains("test") || !split.at("test").is_array()) {
    problems.error(split_path, "must be {\"train\": [...], \"test\": [...]}",
                   "use the split.json of the NeRAF repository");
    return false;
  }
  std::set<std::string> seen;
  for (const char* name : {"train", "test"}) {
    const json& list = split.at(name);
    for (size_t k = 0; k < list.size(); ++k) {
      SoundSpacesEntry e;
      e.train = std::string(name) == "train";
      e.where = std::string(name) + "[" + std::to_string(k) + "]";
      if (!list[k].is_string()) {
        problems.error(split_path, e.where + " is not a string",
                       "entries look like \"270/122_44\"");
        continue;
      }
      e.id = list[k].get<std::string>();
      if (!parse_entry(e.id, e.rot, e.receiver, e.source)) {
        problems.error(split_path,
                       e.where + " " + json_quoted(e.id) + " is not \"<rot>/<receiver>_<source>\"",
                       "entries look like \"270/122_44\"");
        continue;
      }
      if (!seen.insert(e.id).second) {
        problems.error(split_path,
                       e.where + " " + json_quoted(e.id) + " is listed twice (duplicate id)",
                       "remove the duplicate entry");
        continue;
      }
      const auto pr = points.find(e.receiver), ps = points.find(e.source);
      if (pr == points.end() || ps == points.end()) {
        problems.error(split_path,
                       e.where + " " + json_quoted(e.id) + " uses point " +
                           std::to_string(pr == points.end() ? e.receiver : e.source) +
                           ", which metadata/points.txt does not define",
                       "use the points.txt and split.json of the same scene");
        continue;
      }
      e.mic = pr->second;
      e.source_position = ps->second;
      use(e);
    }
  }
  return true;
}

// ---- RAF --------------------------------------------------------------------------------------

std::array<const json*, 2> raf_split_lists(const json& split, const std::string& split_path,
                                           ProblemList& problems) {
  auto first_list = [&](const char* name) -> const json* {
    if (!split.is_object() || !split.contains(name) || !split.at(name).is_array() ||
        split.at(name).empty() || !split.at(name).at(0).is_array())
      return nullptr;
    return &split.at(name).at(0);  // NeRAF reads ['train'][0] and ['test'][0]
  };
  const std::array<const json*, 2> lists = {first_list("train"), first_list("test")};
  if (!lists[0] || !lists[1]) {
    problems.error(split_path, "must hold {\"train\": [[ids]], \"test\": [[ids]]}",
                   "use the RAF repository's data-split file of this room");
    return {nullptr, nullptr};
  }
  return lists;
}

std::optional<std::string> raf_split_id(const json& entry, const std::string& where,
                                        const std::string& split_path, ProblemList& problems) {
  std::string id;
  char buf[32];
  if (entry.is_string()) {
    id = entry.get<std::string>();
  } else if (entry.is_number_unsigned()) {
    std::snprintf(buf, sizeof buf, "%06llu",
                  static_cast<unsigned long long>(entry.get<uint64_t>()));
    id = buf;
  } else if (entry.is_number_integer()) {
    std::snprintf(buf, sizeof buf, "%06lld", static_cast<long long>(entry.get<int64_t>()));
    id = buf;
  } else {
    problems.error(split_path, where + " is not an id", "ids are numbers or \"000123\" strings");
    return std::nullopt;
  }
  // A NUL would end the path early ("000001\0x" would read data/000001 a second time), and a
  // newline in the folder named in a message would split it: the release's ids are digits.
  const bool control = std::any_of(id.begin(), id.end(), [](char c) {
    return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
  });
  if (id.empty() || id.find('/') != std::string::npos || control || id == "." || id == "..") {
    problems.error(split_path, where + " " + json_quoted(id) + " is not an id",
                   "ids name folders of data/ (\"000123\"), not paths");
    return std::nullopt;
  }
  return id;
}

std::optional<std::string> raf_padded_id(const std::string& id) {
  if (id.empty()) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(id.c_str(), &end, 10);
  if (errno != 0 || end != id.c_str() + id.size()) return std::nullopt;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06lld", v);
  return std::string(buf);
}

std::optional<RafPose> parse_raf_pose(const std::optional<std::string>& rx_text,
                                      const std::string& rx_path,
                                      const std::optional<std::string>& tx_text,
                                      const std::string& tx_path, ProblemList& problems) {
  std::vector<double> rx, tx;
  if (!rx_text || !read_numbers(*rx_text, 3, rx) || rx.size() != 3) {
    problems.error(rx_path, "missing or not \"x,y,z\"", "restore the file from the RAF release");
    return std::nullopt;
  }
  if (!tx_text || !read_numbers(*tx_text, 7, tx) || tx.size() != 7) {
    problems.error(tx_path, "missing or not \"qx,qy,qz,qw,x,y,z\"",
                   "restore the file from the RAF release");
    return std::nullopt;
  }
  if (!plausible(rx.data(), 3)) {
    problems.error(rx_path,
                   "microphone position has a NaN, infinite or implausible coordinate "
                   "(|x| > 10000 m)",
                   "fix the file (metres) or remove the id from the split");
    return std::nullopt;
  }
  // The quaternion's scale does not matter (it is normalised), but 1e300 components overflow.
  const double qn = std::sqrt(tx[0] * tx[0] + tx[1] * tx[1] + tx[2] * tx[2] + tx[3] * tx[3]);
  if (!plausible(tx.data(), 7) || !(qn > 1e-9)) {
    problems.error(tx_path,
                   "source pose has a NaN, infinite or implausible value (|x| > 10000) or a "
                   "zero quaternion",
                   "fix the file (qx,qy,qz,qw,x,y,z in metres) or remove the id from the split");
    return std::nullopt;
  }
  RafPose p;
  p.mic = {rx[0], rx[1], rx[2]};
  p.source = {tx[4], tx[5], tx[6]};
  p.q = {tx[0], tx[1], tx[2], tx[3]};
  // Omni microphones: the orientation is the SOURCE yaw, scipy 'yxz' Euler angle about y.
  p.yaw_deg = geometry::yaw_yxz_deg(p.q);
  // R[1][1] is the y component of the rotated up axis R·(0, 1, 0): cos of the tilt.
  const geometry::RotMat r = geometry::quaternion_to_matrix(p.q);
  p.tilt_deg = std::acos(std::clamp(r[1][1], -1.0, 1.0)) * 180.0 / M_PI;
  if (p.tilt_deg > kMaxSourceTiltDeg) {
    char what[200];
    std::snprintf(what, sizeof what,
                  "the source is tilted %.0f° from upright (a rotation about x or z); NeRAF uses "
                  "only its yaw (%.1f°), so the tilt is ignored",
                  p.tilt_deg, p.yaw_deg);
    problems.warning(tx_path, what,
                     "check the quaternion (qx,qy,qz,qw, real last); a loudspeaker on its side "
                     "is modelled as if upright");
  }
  return p;
}

}  // namespace neraf::data::detail
