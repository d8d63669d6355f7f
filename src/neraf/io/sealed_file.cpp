#include "neraf/io/sealed_file.h"

#include <cstring>

#include "neraf/util/error.h"

namespace neraf::io {
namespace {

void put_u32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
void put_u64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}
uint64_t get_le(std::string_view bytes, size_t offset, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i)
    v |= static_cast<uint64_t>(static_cast<uint8_t>(bytes[offset + i])) << (8 * i);
  return v;
}

}  // namespace

uint64_t fnv1a64(std::string_view bytes) {
  uint64_t h = 0xcbf29ce484222325ull;  // the FNV-1a 64 offset basis
  for (const char c : bytes) {
    h ^= static_cast<uint8_t>(c);
    h *= 1099511628211ull;
  }
  return h;
}

std::string seal(std::string_view magic, uint32_t version, std::string_view payload) {
  require(magic.size() == 8, "seal: the magic must be 8 bytes");
  std::string out;
  out.reserve(kSealHeaderBytes + payload.size());
  out.append(magic);
  put_u32(out, version);
  put_u32(out, 0);
  put_u64(out, payload.size());
  put_u64(out, fnv1a64(payload));
  out.append(payload);
  return out;
}

bool has_magic(std::string_view file, std::string_view magic) {
  return file.size() >= magic.size() && file.substr(0, magic.size()) == magic;
}

Unsealed unseal(std::string_view file, std::string_view magic, uint32_t max_version,
                const std::string& path) {
  require(has_magic(file, magic), path + ": not a " + std::string(magic) + " file (wrong magic)");
  require(file.size() >= kSealHeaderBytes,
          path + ": truncated (" + std::to_string(file.size()) + " bytes, shorter than its header)");
  Unsealed out;
  out.version = static_cast<uint32_t>(get_le(file, 8, 4));
  require(out.version >= 1, path + ": damaged (format version 0)");
  require(out.version <= max_version,
          path + ": format version " + std::to_string(out.version) + " is newer than this neraf (" +
              std::to_string(max_version) + "); use the neraf that wrote it or a newer one");
  // Found by fuzz/fuzz_sealed_file: a non-zero reserved field passed, so two different files
  // unsealed to one payload.
  require(get_le(file, 12, 4) == 0, path + ": damaged (the reserved header field is not zero)");
  const uint64_t size = get_le(file, 16, 8);
  const uint64_t have = file.size() - kSealHeaderBytes;
  require(size == have, path + ": truncated or extended (" + std::to_string(have) +
                            " payload bytes, the header says " + std::to_string(size) + ")");
  out.payload = file.substr(kSealHeaderBytes);
  require(fnv1a64(out.payload) == get_le(file, 24, 8),
          path + ": damaged (checksum mismatch: its bytes changed after it was written)");
  return out;
}

}  // namespace neraf::io
