// data::detail::parse_transforms_json (a nerfstudio transforms.json, data/transforms_json.h) on any
// bytes, then split_transforms under each eval mode. The parser reports every problem through the
// ProblemList and never throws; what it accepts must keep its header's promises: a pose marked
// valid is finite, rigid-looking and near, a size marked given is whole pixels, paths are unique
// and sorted, and a split covers each frame at most once per side. Anything else is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "common.h"
#include "neraf/data/transforms_json.h"

using neraf::data::ProblemList;
namespace detail = neraf::data::detail;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  ProblemList problems;
  const detail::Transforms t =
      detail::parse_transforms_json(text, "scene/transforms.json", "scene", "", problems);
  NERAF_FUZZ_CHECK(t.frames.empty() || t.orientation == "up" || t.orientation == "none");
  std::set<std::string> paths;
  for (const detail::TransformsFrame& f : t.frames) {
    NERAF_FUZZ_CHECK(paths.insert(f.path).second);  // duplicates are dropped
    if (f.pose_ok)
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) NERAF_FUZZ_CHECK(std::isfinite(f.pose[r][c]));
        NERAF_FUZZ_CHECK(std::abs(f.pose[r][3]) <= detail::kMaxAbsTranslation);
      }
    if (f.has_size)
      NERAF_FUZZ_CHECK(f.intr.width >= 1 && f.intr.width <= detail::kMaxImageSide &&
                       f.intr.height >= 1 && f.intr.height <= detail::kMaxImageSide);
  }
  for (const neraf::data::Problem& p : problems.items()) NERAF_FUZZ_CHECK(!p.what.empty());
  if (t.frames.empty()) return 0;  // the loader stops there

  const int64_t n = static_cast<int64_t>(t.frames.size());
  for (const char* mode : {"auto", "filename", "fraction"}) {
    ProblemList split_problems;
    std::vector<int64_t> train, eval;
    std::string used;
    detail::split_transforms(t, mode, 0.9, split_problems, train, eval, used);
    NERAF_FUZZ_CHECK(used == "lists" || used == "filename" || used == "fraction");
    for (const std::vector<int64_t>* side : {&train, &eval}) {
      std::set<int64_t> seen;
      for (int64_t i : *side) NERAF_FUZZ_CHECK(i >= 0 && i < n && seen.insert(i).second);
    }
    // The fraction split puts every frame on exactly one side.
    if (used == "fraction")
      NERAF_FUZZ_CHECK(static_cast<int64_t>(train.size() + eval.size()) == n && !train.empty());
  }
  return 0;
}
