// io::unseal on arbitrary bytes: the envelope of checkpoints and calibration files (magic,
// version, payload size, FNV-1a checksum). It promises a neraf::Error for any damaged file and,
// when it accepts one, a payload that is exactly the file after its header.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "common.h"
#include "neraf/io/sealed_file.h"
#include "neraf/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view file(reinterpret_cast<const char*>(data), size);
  try {
    const neraf::io::Unsealed u = neraf::io::unseal(file, "NERAFCKP", 1, "input.pt");
    NERAF_FUZZ_CHECK(u.version == 1);
    NERAF_FUZZ_CHECK(u.payload.size() + neraf::io::kSealHeaderBytes == size);
    NERAF_FUZZ_CHECK(neraf::io::seal("NERAFCKP", 1, u.payload) == file);  // round trip
  } catch (const neraf::Error&) {
    // The documented outcome for a bad file.
  }
  return 0;
}
