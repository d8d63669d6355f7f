#pragma once
// A payload sealed against truncation and corruption, for files whose own format cannot tell
// (LibTorch archives: a flipped byte in a tensor loads as a changed weight). Layout:
//   offset 0   magic                  8 bytes (e.g. "NERAFCKP")
//          8   format version         uint32 little-endian
//         12   reserved (0)           uint32
//         16   payload size P         uint64
//         24   FNV-1a 64 of payload   uint64        (file size = 32 + P)
//         32   payload
#include <cstdint>
#include <string>
#include <string_view>

namespace neraf::io {

constexpr size_t kSealHeaderBytes = 32;

// The sealed bytes of `payload` (`magic` is exactly 8 characters).
std::string seal(std::string_view magic, uint32_t version, std::string_view payload);

struct Unsealed {
  uint32_t version = 0;
  std::string_view payload;  // points into the `file` given to unseal
};

// Checks magic, version (≤ max_version), size and checksum of `file`, the bytes of `path`;
// neraf::Error naming `path` and what is wrong (foreign, newer, truncated, damaged) otherwise.
Unsealed unseal(std::string_view file, std::string_view magic, uint32_t max_version,
                const std::string& path);

// Whether `file` starts with `magic` (to tell a sealed file from a legacy one).
bool has_magic(std::string_view file, std::string_view magic);

// FNV-1a 64 (the checksum; the same function as the runtime's model files, which cannot link
// neraf's stages).
uint64_t fnv1a64(std::string_view bytes);

}  // namespace neraf::io
