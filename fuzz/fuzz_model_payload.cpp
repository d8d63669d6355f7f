// rt::parse_model on a model file around arbitrary payload bytes (model_envelope.h): the header
// size, the JSON header (every field, its range and type), check_model_data's shape and STFT
// checks, and reading the arrays. Then the writer and the reader must agree: a model the reader
// accepts and the writer can write (its metadata is JSON, its strings UTF-8) reads back the same.
// parse_model throws only ModelFileError (or std::bad_alloc); anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <new>
#include <vector>

#include "common.h"
#include "model_envelope.h"
#include "neraf/runtime/model_file.h"

namespace {

namespace rt = neraf::rt;

bool same_layers(const std::vector<rt::DenseLayer>& a, const std::vector<rt::DenseLayer>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].in != b[i].in || a[i].out != b[i].out || a[i].weight != b[i].weight ||
        a[i].bias != b[i].bias)
      return false;
  }
  return true;
}

// Everything the file stores (the metadata may be re-serialised, so it is compared as JSON).
bool same_model(const rt::ModelData& a, const rt::ModelData& b) {
  return a.neraf_version == b.neraf_version && a.layout == b.layout &&
         a.sample_rate == b.sample_rate && a.channels == b.channels && a.n_fft == b.n_fft &&
         a.win_length == b.win_length && a.hop_length == b.hop_length && a.n_freq == b.n_freq &&
         a.max_len == b.max_len && a.waveform_length == b.waveform_length &&
         a.box_min == b.box_min && a.box_max == b.box_max &&
         a.relative_geometry == b.relative_geometry &&
         a.position_max_freq_exp == b.position_max_freq_exp && a.extent_m == b.extent_m &&
         a.leaky_slope == b.leaky_slope && a.output_scale == b.output_scale &&
         same_layers(a.trunk, b.trunk) && same_layers(a.heads, b.heads) &&
         a.calibration == b.calibration && a.bf16_storage == b.bf16_storage &&
         a.metadata_json == b.metadata_json;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::vector<uint8_t> file = neraf::fuzz::wrap_payload(data, size);
  rt::ModelData m;
  try {
    m = rt::parse_model(file.data(), file.size(), "model.nrf");
  } catch (const rt::ModelFileError& e) {
    NERAF_FUZZ_CHECK(e.status() == NERAF_ERR_FORMAT);  // the envelope's version is current
    return 0;
  } catch (const std::bad_alloc&) {
    return 0;  // documented (under ASan a huge request is reported before it could be thrown)
  }

  std::vector<uint8_t> again;
  try {
    again = rt::serialize_model(m, "model.nrf");
  } catch (const rt::ModelFileError&) {
    return 0;  // the writer is stricter than the reader about metadata_json; nothing to compare
  }
  const rt::ModelData back = rt::parse_model(again.data(), again.size(), "again.nrf");
  NERAF_FUZZ_CHECK(same_model(m, back));
  return 0;
}
