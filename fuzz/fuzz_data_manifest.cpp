// What commands read back from a run's RUN/data.json (infer/run_manifest.h) on any JSON text: the
// scenes of a multi-scene run (scene_names, find_scene), the dataset paths (check_data_paths),
// each scene's "audio" entry (audio_info_from_manifest) and its cameras' intrinsics
// (intrinsics_from_json). JSON that neraf::parse_json refuses is its documented neraf::Error
// (fuzz_json_file covers that parser). A damaged manifest is documented as one neraf::Error; what
// the functions accept must keep their promises (a scene index in range, an audio entry whose
// sizes agree and whose box is finite and not inside out, intrinsics that are positive and
// round-trip through intrinsics_json). Anything else is a finding: an exception of another type,
// a sanitizer report.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "common.h"
#include "neraf/infer/run_manifest.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace infer = neraf::infer;

namespace {

const std::string kPath = "run/data.json";

void check_intrinsics(const nlohmann::json& j) {
  neraf::data::Intrinsics k;
  try {
    k = infer::intrinsics_from_json(j, kPath + ": intrinsics");
  } catch (const neraf::Error&) {
    return;
  }
  NERAF_FUZZ_CHECK(k.fx > 0 && k.fy > 0 && std::isfinite(k.fx) && std::isfinite(k.fy));
  NERAF_FUZZ_CHECK(k.width >= 1 && k.width <= 16384 && k.height >= 1 && k.height <= 16384);
  const neraf::data::Intrinsics back =
      infer::intrinsics_from_json(infer::intrinsics_json(k), "round trip");
  NERAF_FUZZ_CHECK(infer::intrinsics_json(back) == infer::intrinsics_json(k));
}

void check_scene(const nlohmann::json& m) {
  if (!m.is_object()) return;  // loading refuses it as "not a neraf run data manifest"
  if (m.contains("audio")) {
    try {
      const infer::AudioRunInfo a = infer::audio_info_from_manifest(m["audio"], kPath);
      NERAF_FUZZ_CHECK(a.sample_rate >= 1 && a.channels >= 1 && a.stft.n_fft >= 2);
      NERAF_FUZZ_CHECK(a.stft.win_length >= 1 && a.stft.win_length <= a.stft.n_fft);
      NERAF_FUZZ_CHECK(a.stft.hop_length >= 1 && a.stft.hop_length <= a.stft.win_length);
      NERAF_FUZZ_CHECK(a.n_freq == a.stft.n_freq() && a.max_len >= 2 && a.waveform_length >= 1);
      for (int k = 0; k < 3; ++k)
        NERAF_FUZZ_CHECK(std::isfinite(a.aabb.min[k]) && std::isfinite(a.aabb.max[k]) &&
                         a.aabb.min[k] <= a.aabb.max[k]);
    } catch (const neraf::Error&) {
      // The documented outcome for a damaged audio entry.
    }
  }
  if (m.contains("default_intrinsics")) check_intrinsics(m["default_intrinsics"]);
  if (m.contains("eval_intrinsics") && m["eval_intrinsics"].is_array())
    for (const nlohmann::json& k : m["eval_intrinsics"]) check_intrinsics(k);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  nlohmann::json m;
  try {
    m = neraf::parse_json(std::string(reinterpret_cast<const char*>(data), size), kPath);
  } catch (const neraf::Error&) {
    return 0;
  }
  const std::vector<std::string> names = infer::scene_names(m);
  NERAF_FUZZ_CHECK(infer::is_multiscene(m) || names.empty());
  std::vector<std::string> selectors = {"0", "1", "999999999", "x"};
  if (!names.empty()) selectors.push_back(names.back());
  for (const std::string& selector : selectors) {
    try {
      const int64_t s = infer::find_scene(m, selector, "run", "--scene");
      NERAF_FUZZ_CHECK(s >= 0 && s < static_cast<int64_t>(names.size()));
    } catch (const neraf::Error&) {
      // The documented outcome for a scene the run does not have.
    }
  }
  try {
    infer::check_data_paths(m, kPath);
  } catch (const neraf::Error&) {
    // The documented outcome for a dataset path holding a control character.
  }
  if (infer::is_multiscene(m))
    for (const nlohmann::json& scene : m["scenes"]) check_scene(scene);
  else
    check_scene(m);
  return 0;
}
