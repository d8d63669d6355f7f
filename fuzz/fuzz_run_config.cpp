// infer::train_config_from_json (a run's RUN/config.json, infer/train_config.h) on any JSON text:
// the preset it names, then every key's type and range through the config's field tables, unknown
// keys refused. JSON that neraf::parse_json refuses is its documented neraf::Error (fuzz_json_file
// covers that parser). A bad config is documented as one neraf::Error; a config it accepts must
// survive its own round trip (to_json → train_config_from_json gives the same JSON again), and the
// radiance field's part of it passes or fails nerf::validate with a neraf::Error only. Anything
// else is a finding. (infer::validate, the range checks of the whole config, asks the acoustic
// stage for its scene encoder's smallest grid and needs LibTorch: not fuzzed here.)
#include <cstddef>
#include <cstdint>
#include <string>

#include "common.h"
#include "neraf/infer/train_config.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace infer = neraf::infer;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = "run/config.json";
  nlohmann::json j;
  try {
    j = neraf::parse_json(std::string(reinterpret_cast<const char*>(data), size), path);
  } catch (const neraf::Error&) {
    return 0;
  }
  infer::TrainConfig c;
  try {
    c = infer::train_config_from_json(j, path);
  } catch (const neraf::Error&) {
    return 0;  // the documented outcome for a bad config
  }
  const nlohmann::json resolved = infer::to_json(c);
  // A neraf::Error here escapes: the JSON of an accepted config must read back.
  const infer::TrainConfig again = infer::train_config_from_json(resolved, "resolved config");
  NERAF_FUZZ_CHECK(infer::to_json(again) == resolved);
  try {
    neraf::nerf::validate(c.model, path + ".model");
  } catch (const neraf::Error&) {
    // The documented outcome for model sizes out of range.
  }
  return 0;
}
