// io::read_npy_header and io::read_npy on arbitrary bytes: the magic, the version-dependent
// header length, the Python-dict header text (descr, fortran_order, shape) and the data size.
// Both promise a neraf::Error for any file they reject; anything else is a finding.
#include <cstddef>
#include <cstdint>

#include "common.h"
#include "neraf/io/npy.h"
#include "neraf/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = neraf::fuzz::write_input(data, size, ".npy");
  try {
    const neraf::io::NpyHeader h = neraf::io::read_npy_header(path);
    NERAF_FUZZ_CHECK(h.element_size == 4 || h.element_size == 8);
    for (const int64_t d : h.shape) NERAF_FUZZ_CHECK(d >= 0);
    // The header check promises that the data is there, so the array fits in the input.
    NERAF_FUZZ_CHECK(h.data_offset + h.num_elements() * h.element_size <= int64_t(size));

    const neraf::io::NpyArray a = neraf::io::read_npy(path);
    NERAF_FUZZ_CHECK(a.shape == h.shape);
    NERAF_FUZZ_CHECK(int64_t(a.data.size()) == h.num_elements());
  } catch (const neraf::Error&) {
    // The documented outcome for a bad file.
  }
  return 0;
}
