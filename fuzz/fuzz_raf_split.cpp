// data::detail::raf_split_lists, raf_split_id and raf_padded_id (RAF metadata/data-split.json,
// data/pose_files.h) on any JSON text, walked as index_raf walks it. JSON that neraf::parse_json
// refuses is its documented neraf::Error (fuzz_json_file covers that parser). The split functions
// report every problem through the ProblemList and never throw; an id they accept is a plain
// folder name of data/ (never a path, no control character), a padded id is a whole number of at
// least 6 digits, and every problem is one line. Anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "common.h"
#include "neraf/data/pose_files.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace detail = neraf::data::detail;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = "room/metadata/data-split.json";
  nlohmann::json split;
  try {
    split = neraf::parse_json(std::string(reinterpret_cast<const char*>(data), size), path);
  } catch (const neraf::Error&) {
    return 0;
  }
  neraf::data::ProblemList problems;
  const auto lists = detail::raf_split_lists(split, path, problems);
  NERAF_FUZZ_CHECK((lists[0] == nullptr) == (lists[1] == nullptr));
  if (!lists[0]) {
    NERAF_FUZZ_CHECK(problems.num_errors() == 1);
    return 0;
  }
  NERAF_FUZZ_CHECK(problems.items().empty() && lists[0]->is_array() && lists[1]->is_array());
  for (int li = 0; li < 2; ++li)
    for (size_t k = 0; k < lists[li]->size(); ++k) {
      const std::string where =
          std::string(li == 0 ? "train" : "test") + "[0][" + std::to_string(k) + "]";
      const auto before = problems.items().size();
      const auto id = detail::raf_split_id((*lists[li])[k], where, path, problems);
      NERAF_FUZZ_CHECK(problems.items().size() == before + (id ? 0 : 1));
      if (!id) {
        // One line: the id is quoted with JSON escapes (a NUL or newline would cut or split it).
        NERAF_FUZZ_CHECK(problems.items().back().to_string().find_first_of(
                             std::string("\n\0", 2)) == std::string::npos);
        continue;
      }
      NERAF_FUZZ_CHECK(!id->empty() && *id != "." && *id != ".." &&
                       id->find('/') == std::string::npos);
      for (char c : *id) NERAF_FUZZ_CHECK(static_cast<unsigned char>(c) >= 0x20 && c != 0x7f);
      if (const auto padded = detail::raf_padded_id(*id)) {
        NERAF_FUZZ_CHECK(padded->size() >= 6);
        NERAF_FUZZ_CHECK(padded->find_first_not_of("-0123456789") == std::string::npos);
      }
    }
  return 0;
}
