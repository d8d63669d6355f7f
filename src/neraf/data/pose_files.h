#pragma once
// Internal to data/: the pose and split files of the SoundSpaces and RAF layouts
// (neraf-reference.md §3.2-3.3), parsed from their text or JSON without touching the disk and
// without LibTorch, so that fuzz/ can feed them any bytes. soundspaces.cpp and raf.cpp read the
// files, call these and check the RIR files the entries name. Every problem names the file (and
// line or entry) at fault, as the loaders report it.
#include <array>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "neraf/data/problem.h"
#include "neraf/geometry/pose.h"
#include "neraf/geometry/vec.h"

namespace neraf::data::detail {

// Largest |coordinate| accepted in a pose file (m), rir_check.h's kMaxAbsCoordinate (raf.cpp
// checks that they agree; rir_check.h needs LibTorch, this file must not).
constexpr double kMaxAbsPoseCoordinate = 1e4;

// The whole of a pose or split file; nullopt when it is missing, cannot be read or is not a
// regular file (a FIFO or a device would block the read or never end).
std::optional<std::string> read_file_text(const std::string& path);

// ---- SoundSpaces ------------------------------------------------------------------------------

// metadata/points.txt (`text`, read from `path`): one point per line, "idx<TAB>x<TAB>y<TAB>z"
// (any white space; blank lines skipped), Habitat y-up, returned as idx → [x, z, −y], the frame
// NeRAF uses. A line that is not exactly an integer index and three numbers, an index out of
// range, an implausible coordinate or an index given twice is an error naming the line; the
// point is left out.
std::map<long, geometry::Vec3> parse_points_txt(const std::string& text, const std::string& path,
                                                ProblemList& problems);

struct SoundSpacesEntry {
  bool train = true;  // from the "train" list, else "test"
  std::string where;  // "train[3]", for messages
  std::string id;     // the entry as written: "<rot>/<receiver>_<source>", e.g. "270/122_44"
  int rot = 0;        // receiver heading (degrees)
  long receiver = 0, source = 0;  // point indices
  geometry::Vec3 mic, source_position;
};

// split.json (`split`, read from `split_path`): {"train": ["<rot>/<r>_<s>", ...], "test": [...]}.
// Calls use(entry) for each entry that is well formed, listed once and whose points `points`
// defines, in file order (train, then test), so that the caller's checks of the entry's files
// are reported in order with the entries' own problems. False (with an error) when the file does
// not have the two lists at all.
bool parse_soundspaces_split(const nlohmann::json& split, const std::string& split_path,
                             const std::map<long, geometry::Vec3>& points, ProblemList& problems,
                             const std::function<void(const SoundSpacesEntry&)>& use);

// ---- RAF --------------------------------------------------------------------------------------

// data-split.json (`split`, read from `split_path`): the lists NeRAF reads, ['train'][0] and
// ['test'][0]; nullptrs (with an error) when the file is not {"train": [[ids]], "test": [[ids]]}.
std::array<const nlohmann::json*, 2> raf_split_lists(const nlohmann::json& split,
                                                     const std::string& split_path,
                                                     ProblemList& problems);

// Entry `where` ("train[0][5]") of a split list as the name of its folder in data/: a number
// zero-padded to 6 digits ("000123", the release's folder names), or a string as written;
// nullopt (with an error) for anything else or a string that is not a plain folder name (a
// path, ".", "..", a control character).
std::optional<std::string> raf_split_id(const nlohmann::json& entry, const std::string& where,
                                        const std::string& split_path, ProblemList& problems);

// A string id written without the zero padding of the folder names ("123" → "000123");
// nullopt when `id` is not a whole number.
std::optional<std::string> raf_padded_id(const std::string& id);

struct RafPose {
  geometry::Vec3 mic;      // rx_pos.txt (m)
  geometry::Vec3 source;   // tx_pos.txt's position (m)
  geometry::Quaternion q;  // tx_pos.txt's orientation (real last), as written (not normalised)
  double yaw_deg = 0;      // the source yaw NeRAF uses: scipy as_euler('yxz')[0], not rounded
  double tilt_deg = 0;     // how far the source's up axis leans from +y (what the yaw drops)
};

// A source tilted further than this from upright (its up axis from +y) gets a warning: NeRAF
// keeps only the yaw. A loudspeaker standing upright, measured with a few degrees of error,
// stays below it.
constexpr double kMaxSourceTiltDeg = 10.0;

// rx_pos.txt ("x,y,z") and tx_pos.txt ("qx,qy,qz,qw,x,y,z"), one line each, numbers separated by
// commas and/or white space; a missing file is nullopt. nullopt with an error naming the file at
// fault when one is missing, has another count of numbers, an implausible coordinate or a zero
// quaternion; a source tilted more than kMaxSourceTiltDeg is a warning naming tx_pos.txt.
std::optional<RafPose> parse_raf_pose(const std::optional<std::string>& rx_text,
                                      const std::string& rx_path,
                                      const std::optional<std::string>& tx_text,
                                      const std::string& tx_path, ProblemList& problems);

}  // namespace neraf::data::detail
