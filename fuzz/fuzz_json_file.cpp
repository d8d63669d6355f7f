// io::read_json on arbitrary bytes: every JSON file neraf reads from a user (configs, manifests,
// scenes) goes through it. Its header promises errors that name the file, i.e. a neraf::Error;
// any other exception (a raw nlohmann one) or a crash is a finding.
#include <cstddef>
#include <cstdint>

#include "common.h"
#include "neraf/io/json_file.h"
#include "neraf/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = neraf::fuzz::write_input(data, size, ".json");
  try {
    const nlohmann::json j = neraf::io::read_json(path);
    NERAF_FUZZ_CHECK(!j.is_discarded());
  } catch (const neraf::Error&) {
    // The documented outcome for a file that is not JSON.
  }
  return 0;
}
