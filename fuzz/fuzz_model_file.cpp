// rt::parse_model on arbitrary bytes, as read_model_file hands it a whole MODEL.nrf: the magic,
// version, flags, payload size and checksum checks (fuzz_model_payload gets past the checksum to
// the header JSON and the arrays). parse_model promises to read only inside the input and to
// throw only ModelFileError (or std::bad_alloc); anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <new>

#include "common.h"
#include "neraf/runtime/model_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const neraf::rt::ModelData m = neraf::rt::parse_model(data, size, "model.nrf");
    NERAF_FUZZ_CHECK(!m.trunk.empty() && m.heads.size() == size_t(m.channels));
  } catch (const neraf::rt::ModelFileError& e) {
    // The documented outcome for a bad file, with one of the documented statuses.
    NERAF_FUZZ_CHECK(e.status() == NERAF_ERR_FORMAT || e.status() == NERAF_ERR_VERSION);
  } catch (const std::bad_alloc&) {
    // Documented too (and, under ASan, a huge request is reported before it could be thrown).
  }
  return 0;
}
