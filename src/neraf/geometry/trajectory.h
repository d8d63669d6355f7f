#pragma once
// Timed listener paths (`neraf render trajectory --path PATH.json`) and pose lists (`neraf render
// rir --poses POSES.json`): their JSON formats, validation and interpolation. docs/PATH_FORMAT.md
// is the user's description; this header is the contract the renderers build on.
//
// Positions are metres in the dataset's frame and the yaw is degrees, exactly as `neraf render
// rir --mic/--src/--yaw` take them (see audio_pose_help() in cli/render_audio.cpp). Every
// problem in a file is one neraf::Error line naming the file, the JSON path and the fix, e.g.
//   path.json: keyframes[3].time: 1.5 is not after keyframes[2].time (2); ...
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/geometry/vec.h"

namespace neraf::geometry {

// The formats this neraf reads ("version" in both files).
constexpr int kPathFormatVersion = 1;
// Bounds that catch unit mistakes (millimetres, a stray exponent) and keep allocation sane; the
// counts are checked before anything is allocated for them.
constexpr double kMaxAbsCoordinateM = 1e6;         // |x|, |y|, |z| of any position
constexpr double kMaxAbsYawDeg = 1e6;              // |yaw| as written
constexpr double kMaxTimeS = 1e6;                  // keyframe times are in [0, kMaxTimeS]
constexpr size_t kMaxKeyframes = 100000;           // keyframes in one path
constexpr size_t kMaxPoses = 100000;               // poses in one pose list
constexpr size_t kMaxPoseNameLength = 100;         // characters of a pose name (a file name stem)
constexpr double kMaxSampleRateHz = 1000.0;        // sample_trajectory's rate_hz
constexpr size_t kMaxTrajectorySamples = 1000000;  // poses sample_trajectory returns

// One pose at a time. yaw_deg is in [0, 360): files may write any angle, it is wrapped on parsing.
struct TimedPose {
  double time = 0;  // seconds from the start of the rendering
  Vec3 mic;
  Vec3 source;
  double yaw_deg = 0;
};

struct Trajectory {
  std::vector<TimedPose> keyframes;  // at least one, times strictly increasing, all >= 0
  // True when the file gives a "source" per keyframe (the source may move), false for one
  // top-level "source" (every keyframe then carries that same position).
  bool moving_source = false;

  // The time of the last keyframe: the path starts at t = 0, so that is how long it lasts.
  double duration() const;

  // The pose at time t (its .time is t): positions interpolated linearly between the keyframes
  // around t, yaw along the shorter arc (359 → 1 passes through 0; a half turn turns towards
  // increasing yaw, i.e. left), the result wrapped to [0, 360). Before the first keyframe (and
  // for NaN) the first keyframe's pose, after the last the last's. Throws Error when empty.
  TimedPose at(double t) const;
};

// Poses at t = k / rate_hz for k = 0, 1, ... while t < duration_s (so duration_s·rate_hz of
// them, rounded up). Errors (neraf::Error) when rate_hz is not in (0, kMaxSampleRateHz], when
// duration_s is not a positive finite number, or when that would be more than
// kMaxTrajectorySamples poses.
std::vector<TimedPose> sample_trajectory(const Trajectory& trajectory, double rate_hz,
                                         double duration_s);

// The path in `j`; `where` names it in errors (normally the file's path). Never throws anything
// but neraf::Error.
Trajectory parse_trajectory(const nlohmann::json& j, const std::string& where);
// Reads and parses the file at `path`; a missing, unreadable or malformed file is one Error.
Trajectory load_trajectory(const std::string& path);

// One pose of a pose list. yaw_deg is wrapped to [0, 360) like TimedPose's.
struct NamedPose {
  std::string name;  // unique; safe as a file name stem ([A-Za-z0-9._-], not starting with '.')
  Vec3 mic;
  Vec3 source;
  double yaw_deg = 0;
};

// The name a pose without "name" gets: pose_0000, pose_0001, ... (its index, 4 digits or more).
std::string default_pose_name(size_t index);

// The poses in `j`, in file order; `where` names it in errors. Never throws anything but
// neraf::Error.
std::vector<NamedPose> parse_pose_list(const nlohmann::json& j, const std::string& where);
// Reads and parses the file at `path`; a missing, unreadable or malformed file is one Error.
std::vector<NamedPose> load_pose_list(const std::string& path);

}  // namespace neraf::geometry
