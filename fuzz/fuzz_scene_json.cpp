// sim::scene_from_json (docs/SCENE_FORMAT.md) on any JSON value: every key's type check, then
// validate_scene (materials, boxes in the room, free-space checks, the microphone grid). Every
// error is documented as one neraf::Error line; a scene it accepts must survive its own round
// trip (scene_to_json is "parseable by scene_from_json", and gives the same JSON again).
// Anything else is a finding. Input that is not JSON is skipped (fuzz_json_file's job).
#include <cstddef>
#include <cstdint>

#include "common.h"
#include "neraf/sim/scene_json.h"
#include "neraf/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const nlohmann::json j = nlohmann::json::parse(data, data + size, nullptr,
                                                 /*allow_exceptions=*/false);
  if (j.is_discarded()) return 0;
  neraf::sim::Scene scene;
  try {
    scene = neraf::sim::scene_from_json(j, "scene.json");
  } catch (const neraf::Error&) {
    return 0;  // the documented outcome for a bad scene
  }
  const nlohmann::json resolved = neraf::sim::scene_to_json(scene);
  // A neraf::Error here escapes: the resolved scene of an accepted one must parse.
  const neraf::sim::Scene again = neraf::sim::scene_from_json(resolved, "resolved scene");
  NERAF_FUZZ_CHECK(neraf::sim::scene_to_json(again) == resolved);
  return 0;
}
