// geometry::parse_trajectory and geometry::parse_pose_list (docs/PATH_FORMAT.md) on any JSON
// value, then the interpolation of an accepted path (Trajectory::at, sample_trajectory). Both
// parsers promise never to throw anything but neraf::Error; their results must keep the
// guarantees of trajectory.h (strictly increasing times, yaw in [0, 360), bounded coordinates,
// unique safe names). Anything else is a finding. Input that is not JSON is skipped: parsing
// JSON text is fuzz_json_file's and fuzz_trajectory_file's job.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>

#include "common.h"
#include "neraf/geometry/trajectory.h"
#include "neraf/util/error.h"

namespace {

namespace g = neraf::geometry;

bool valid_yaw(double yaw) { return yaw >= 0.0 && yaw < 360.0; }

bool valid_position(const g::Vec3& p) {
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(p[a]) <= g::kMaxAbsCoordinateM)) return false;
  }
  return true;
}

// A pose interpolated from the keyframes stays within their bounding values.
void check_pose(const g::TimedPose& p) {
  NERAF_FUZZ_CHECK(valid_yaw(p.yaw_deg));
  NERAF_FUZZ_CHECK(valid_position(p.mic));
  NERAF_FUZZ_CHECK(valid_position(p.source));
}

void check_trajectory(const g::Trajectory& tr) {
  NERAF_FUZZ_CHECK(!tr.keyframes.empty() && tr.keyframes.size() <= g::kMaxKeyframes);
  for (size_t i = 0; i < tr.keyframes.size(); ++i) {
    const g::TimedPose& k = tr.keyframes[i];
    NERAF_FUZZ_CHECK(k.time >= 0.0 && k.time <= g::kMaxTimeS);
    if (i > 0) NERAF_FUZZ_CHECK(k.time > tr.keyframes[i - 1].time);
    check_pose(k);
    if (!tr.moving_source) {
      const g::Vec3& s0 = tr.keyframes[0].source;
      NERAF_FUZZ_CHECK(k.source.x == s0.x && k.source.y == s0.y && k.source.z == s0.z);
    }
  }
  NERAF_FUZZ_CHECK(tr.duration() == tr.keyframes.back().time);

  // at(): before, on, between and after the keyframes, and NaN (documented: the first pose).
  const double d = tr.duration();
  for (const double t : {-1.0, 0.0, 0.25 * d, 0.5 * d, d, d + 1.0, std::nan("")}) {
    const g::TimedPose p = tr.at(t);
    check_pose(p);
    NERAF_FUZZ_CHECK(std::isnan(t) ? std::isnan(p.time) : p.time == t);
  }
  // sample_trajectory at a rate that gives about 200 poses, within its documented limits.
  if (d > 0) {
    const double rate = std::min(g::kMaxSampleRateHz, 200.0 / d);
    if (rate > 0) {
      const auto poses = g::sample_trajectory(tr, rate, d);
      const double expected = std::ceil(d * rate);
      NERAF_FUZZ_CHECK(std::abs(double(poses.size()) - expected) <= 1.0);
      for (size_t k = 0; k < poses.size(); ++k) {
        NERAF_FUZZ_CHECK(poses[k].time == double(k) / rate);
        check_pose(poses[k]);
      }
    }
  }
}

bool safe_name(const std::string& name) {
  if (name.empty() || name.size() > g::kMaxPoseNameLength || name[0] == '.') return false;
  return std::all_of(name.begin(), name.end(), [](unsigned char c) {
    return std::isalnum(c) || c == '-' || c == '_' || c == '.';
  });
}

void check_pose_list(const std::vector<g::NamedPose>& poses) {
  NERAF_FUZZ_CHECK(!poses.empty() && poses.size() <= g::kMaxPoses);
  std::set<std::string> lower_names;
  for (const g::NamedPose& p : poses) {
    NERAF_FUZZ_CHECK(safe_name(p.name));
    std::string lower = p.name;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    NERAF_FUZZ_CHECK(lower_names.insert(lower).second);  // unique, ignoring case
    NERAF_FUZZ_CHECK(valid_yaw(p.yaw_deg));
    NERAF_FUZZ_CHECK(valid_position(p.mic));
    NERAF_FUZZ_CHECK(valid_position(p.source));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr,
                                                 /*allow_exceptions=*/false);
  if (j.is_discarded()) return 0;
  try {
    check_trajectory(g::parse_trajectory(j, "path.json"));
  } catch (const neraf::Error&) {
    // The documented outcome for a bad path.
  }
  try {
    check_pose_list(g::parse_pose_list(j, "poses.json"));
  } catch (const neraf::Error&) {
    // The documented outcome for a bad pose list.
  }
  return 0;
}
