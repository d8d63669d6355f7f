#pragma once
// MODEL.nrf's envelope (runtime/model_file.h: magic, version, flags, payload size, payload,
// FNV-1a checksum) around fuzzer bytes. Random bytes almost never carry a matching checksum, so a
// fuzzer that mutated whole files would spend its time on the checksum test; the payload targets
// mutate the payload (header JSON + arrays) and let this wrap it into a file that passes it.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "neraf/runtime/model_file.h"

namespace neraf::fuzz {

// The flags a writer would have set: bit 0 when the payload asks for bfloat16 weights anywhere (a
// mutated payload can still disagree with them, which the reader must report).
inline uint32_t payload_flags(const uint8_t* payload, size_t size) {
  static constexpr char kBf16[] = "bfloat16";
  const size_t n = sizeof kBf16 - 1;
  for (size_t i = 0; i + n <= size; ++i) {
    if (std::memcmp(payload + i, kBf16, n) == 0) return rt::kModelFlagBf16;
  }
  return 0;
}

inline void append_le(std::vector<uint8_t>& out, uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

// A complete model file whose payload is `payload`, with a correct size and checksum.
inline std::vector<uint8_t> wrap_payload(const uint8_t* payload, size_t size) {
  std::vector<uint8_t> file = {'N', 'E', 'R', 'A', 'F', 'M', 'D', 'L'};
  file.reserve(size + 32);
  append_le(file, rt::kModelFormatVersion, 4);
  append_le(file, payload_flags(payload, size), 4);
  append_le(file, size, 8);
  file.insert(file.end(), payload, payload + size);
  append_le(file, rt::fnv1a64(payload, size), 8);
  return file;
}

}  // namespace neraf::fuzz
