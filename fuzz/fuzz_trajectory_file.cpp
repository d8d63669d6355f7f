// geometry::load_trajectory and geometry::load_pose_list on arbitrary bytes: the file checks and
// the JSON parsing in front of the parsers (fuzz_trajectory checks the parsed results in depth).
// A missing, unreadable or malformed file is documented as one neraf::Error; anything else is a
// finding.
#include <cstddef>
#include <cstdint>

#include "common.h"
#include "neraf/geometry/trajectory.h"
#include "neraf/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = neraf::fuzz::write_input(data, size, ".json");
  try {
    const neraf::geometry::Trajectory tr = neraf::geometry::load_trajectory(path);
    NERAF_FUZZ_CHECK(!tr.keyframes.empty());
  } catch (const neraf::Error&) {
    // The documented outcome for a bad path file.
  }
  try {
    const auto poses = neraf::geometry::load_pose_list(path);
    NERAF_FUZZ_CHECK(!poses.empty());
  } catch (const neraf::Error&) {
    // The documented outcome for a bad pose-list file.
  }
  return 0;
}
