// The C API's load path, neraf_model_load_ex, on a model file around arbitrary payload bytes
// (model_envelope.h) written to a temporary file: read_model_file, then the engine that a loaded
// model builds (folded first layer, time table, Griffin-Lim plans). It loads with
// NERAF_LOAD_FLOAT32 so that what runs does not depend on the CPU (a bfloat16 model would run its
// trunk on AMX tiles only where there are some; tests/runtime covers those kernels). A model that
// loads is queried once (workspace, log-STFT at the centre of its box) when it is small enough for
// a fuzzer's time budget. neraf_rt.h promises that no function aborts or throws: every outcome is a
// status with a message, so any crash, sanitizer report or escaping exception is a finding.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "common.h"
#include "model_envelope.h"
#include "neraf/neraf_rt.h"

namespace {

// Queries beyond this many log-STFT values or RIR samples would make the fuzzer slow, not find
// more: the engine's arithmetic does not depend on the sizes.
constexpr size_t kMaxQueryValues = size_t(1) << 16;

void query_once(const neraf_model* model, const neraf_model_info& info) {
  const size_t values = size_t(info.channels) * size_t(info.n_freq) * size_t(info.n_frames);
  const size_t samples = size_t(info.channels) * size_t(info.rir_length);
  if (values > kMaxQueryValues || samples > 16 * kMaxQueryValues) return;

  neraf_workspace* ws = nullptr;
  if (neraf_workspace_create(model, &ws) != NERAF_OK) {
    NERAF_FUZZ_CHECK(ws == nullptr && neraf_last_error()[0] != '\0');
    return;
  }
  NERAF_FUZZ_CHECK(neraf_workspace_set_threads(ws, 1) == NERAF_OK);
  neraf_pose pose{};
  for (int a = 0; a < 3; ++a) {
    // Halves first: box_min + box_max may overflow for a hostile box.
    pose.mic[a] = pose.source[a] = 0.5 * info.box_min[a] + 0.5 * info.box_max[a];
  }
  std::vector<float> out(values);
  const neraf_status s = neraf_query_log_stft(model, ws, &pose, 0, out.data(), out.size());
  NERAF_FUZZ_CHECK(s == NERAF_OK || neraf_last_error()[0] != '\0');
  neraf_workspace_free(ws);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<uint8_t> file = neraf::fuzz::wrap_payload(data, size);
  const std::string path = neraf::fuzz::write_input(file.data(), file.size(), ".nrf");

  neraf_model* model = nullptr;
  const neraf_status s = neraf_model_load_ex(path.c_str(), NERAF_LOAD_FLOAT32, &model);
  if (s != NERAF_OK) {
    // A failed load leaves no model and says why.
    NERAF_FUZZ_CHECK(model == nullptr);
    NERAF_FUZZ_CHECK(neraf_last_error()[0] != '\0');
    NERAF_FUZZ_CHECK(std::strcmp(neraf_status_string(s), "unknown status") != 0);
    return 0;
  }
  NERAF_FUZZ_CHECK(model != nullptr);
  neraf_model_info info;
  NERAF_FUZZ_CHECK(neraf_model_get_info(model, &info) == NERAF_OK);
  NERAF_FUZZ_CHECK(info.channels >= 1 && info.n_freq >= 2 && info.n_frames >= 2);
  NERAF_FUZZ_CHECK(info.rir_length > 0);
  NERAF_FUZZ_CHECK(std::memchr(info.neraf_version, '\0', sizeof info.neraf_version) != nullptr);
  query_once(model, info);
  neraf_model_free(model);
  return 0;
}
