// data::detail::parse_soundspaces_split (SoundSpaces split.json, data/pose_files.h) on any JSON
// text, against a fixed points.txt of points 0..511. JSON that neraf::parse_json refuses is its
// documented neraf::Error (fuzz_json_file covers that parser). The split parser reports every
// problem through the ProblemList and never throws; the entries it hands on are listed once,
// written as their numbers print (so no two name the same wav) and use defined points; every
// problem is one line. Anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <map>
#include <set>
#include <string>

#include "common.h"
#include "neraf/data/pose_files.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace detail = neraf::data::detail;

namespace {

std::map<long, neraf::geometry::Vec3> fixed_points() {
  std::map<long, neraf::geometry::Vec3> points;
  for (long i = 0; i < 512; ++i) points[i] = {0.01 * i, 1.5, -0.02 * i};
  return points;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::map<long, neraf::geometry::Vec3> points = fixed_points();
  const std::string path = "scene/metadata_AudioNeRF/split.json";
  nlohmann::json split;
  try {
    split = neraf::parse_json(std::string(reinterpret_cast<const char*>(data), size), path);
  } catch (const neraf::Error&) {
    return 0;
  }
  neraf::data::ProblemList problems;
  std::set<std::string> ids;
  const bool lists =
      detail::parse_soundspaces_split(split, path, points, problems, [&](const auto& e) {
        NERAF_FUZZ_CHECK(ids.insert(e.id).second);
        NERAF_FUZZ_CHECK(e.id == std::to_string(e.rot) + "/" + std::to_string(e.receiver) + "_" +
                                     std::to_string(e.source));
        NERAF_FUZZ_CHECK(points.count(e.receiver) && points.count(e.source));
        NERAF_FUZZ_CHECK(e.where.compare(0, e.train ? 6 : 5, e.train ? "train[" : "test[") == 0);
      });
  NERAF_FUZZ_CHECK(lists || (ids.empty() && problems.num_errors() == 1));
  // One line each: entries are quoted with JSON escapes (a NUL or newline would cut or split it).
  for (const neraf::data::Problem& p : problems.items())
    NERAF_FUZZ_CHECK(p.is_error() && p.file == path && !p.fix.empty() &&
                     p.to_string().find_first_of(std::string("\n\0", 2)) == std::string::npos);
  return 0;
}
