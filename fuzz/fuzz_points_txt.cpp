// data::detail::parse_points_txt (SoundSpaces metadata/points.txt, data/pose_files.h) on any
// bytes. The parser reports every bad line through the ProblemList and never throws; the points it
// keeps are finite and within the plausible range, one per accepted line. Anything else is a
// finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "common.h"
#include "neraf/data/pose_files.h"

namespace detail = neraf::data::detail;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  neraf::data::ProblemList problems;
  const auto points = detail::parse_points_txt(text, "scene/metadata/points.txt", problems);
  for (const auto& [id, p] : points)
    for (int k = 0; k < 3; ++k) NERAF_FUZZ_CHECK(std::abs(p[k]) <= detail::kMaxAbsPoseCoordinate);
  size_t lines = 0;
  for (char c : text) lines += c == '\n';
  NERAF_FUZZ_CHECK(points.size() <= lines + 1);
  for (const neraf::data::Problem& p : problems.items())
    NERAF_FUZZ_CHECK(p.is_error() && p.file == "scene/metadata/points.txt" &&
                     p.what.compare(0, 5, "line ") == 0);
  return 0;
}
