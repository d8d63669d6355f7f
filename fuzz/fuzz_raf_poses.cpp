// data::detail::parse_raf_pose (RAF rx_pos.txt and tx_pos.txt, data/pose_files.h) with the input
// as the microphone file beside a valid source file, and as the source file beside a valid
// microphone file. The parser reports every problem through the ProblemList and never throws; a
// pose it accepts is finite and plausible, its yaw in [-180, 180] (so the loader's rounding to
// whole degrees fits an int), and a tilt beyond kMaxSourceTiltDeg is a warning naming tx_pos.txt.
// Anything else is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "common.h"
#include "neraf/data/pose_files.h"

namespace detail = neraf::data::detail;

namespace {

void check(const std::optional<std::string>& rx, const std::optional<std::string>& tx) {
  const std::string rx_path = "room/data/000001/rx_pos.txt";
  const std::string tx_path = "room/data/000001/tx_pos.txt";
  neraf::data::ProblemList problems;
  const auto pose = detail::parse_raf_pose(rx, rx_path, tx, tx_path, problems);
  if (!pose) {
    NERAF_FUZZ_CHECK(problems.num_errors() == 1 && problems.num_warnings() == 0);
    return;
  }
  NERAF_FUZZ_CHECK(problems.num_errors() == 0);
  for (int k = 0; k < 3; ++k)
    NERAF_FUZZ_CHECK(std::abs(pose->mic[k]) <= detail::kMaxAbsPoseCoordinate &&
                     std::abs(pose->source[k]) <= detail::kMaxAbsPoseCoordinate);
  NERAF_FUZZ_CHECK(pose->yaw_deg >= -180.0 && pose->yaw_deg <= 180.0);
  NERAF_FUZZ_CHECK(pose->tilt_deg >= 0.0 && pose->tilt_deg <= 180.0);
  const bool tilted = pose->tilt_deg > detail::kMaxSourceTiltDeg;
  NERAF_FUZZ_CHECK(problems.num_warnings() == (tilted ? 1 : 0));
  if (tilted) NERAF_FUZZ_CHECK(problems.items()[0].file == tx_path);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  check(text, "0,0.25881904510252074,0,0.96592582628906831,3.0,1.5,1.0\n");  // yaw 30°
  check("1.0,1.2,2.0\n", text);
  return 0;
}
