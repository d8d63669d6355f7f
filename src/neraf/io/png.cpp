#include "neraf/io/png.h"

// The implementation of stb_image_write is compiled into Debian's libstb.
#include <stb/stb_image_write.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"

namespace neraf::io {

std::vector<uint8_t> encode_png(int width, int height, int channels, const uint8_t* pixels) {
  require(width > 0 && height > 0 && (channels == 1 || channels == 3 || channels == 4),
          "encode_png: expected a non-empty image with 1, 3 or 4 channels");
  std::vector<uint8_t> bytes;
  const auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<uint8_t>*>(context);
    const auto* p = static_cast<const uint8_t*>(data);
    out->insert(out->end(), p, p + size);
  };
  const int ok =
      stbi_write_png_to_func(append, &bytes, width, height, channels, pixels, width * channels);
  require(ok != 0 && !bytes.empty(), "PNG encoding failed for a " + std::to_string(width) + "x" +
                                         std::to_string(height) + " image");
  return bytes;
}

void write_png(const std::string& path, int width, int height, int channels,
               const uint8_t* pixels) {
  const std::vector<uint8_t> bytes = encode_png(width, height, channels, pixels);
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    require(out.good(), path + ": cannot open for writing (" + std::strerror(errno) +
                            "); choose a writable output path");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.flush();
    require(out.good(), path + ": write failed (disk full?); free space and retry");
  });
}

namespace {

uint32_t crc32(const uint8_t* p, size_t n, uint32_t crc = 0xFFFFFFFFu) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
  return crc;
}

uint32_t be32(const uint8_t* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | uint32_t(p[3]);
}

std::string png_problem(const std::vector<uint8_t>& b) {
  size_t pos = 8;
  bool have_header = false, have_data = false;
  while (true) {
    if (pos + 12 > b.size())
      return have_data ? "cut short: the file ends before its IEND chunk"
                       : "cut short: the file ends before its image data";
    const uint32_t len = be32(&b[pos]);
    if (len > b.size() - pos - 12) return "cut short: a chunk runs past the end of the file";
    const uint8_t* type = &b[pos + 4];
    if (be32(&b[pos + 8 + len]) != (crc32(type, 4 + size_t(len)) ^ 0xFFFFFFFFu))
      return "damaged: the CRC of its " + std::string(reinterpret_cast<const char*>(type), 4) +
             " chunk does not match";
    const std::string t(reinterpret_cast<const char*>(type), 4);
    if (!have_header && t != "IHDR") return "damaged: the first chunk is not IHDR";
    have_header = true;
    if (t == "IDAT") have_data = true;
    if (t == "IEND") return have_data ? "" : "damaged: no image data (IDAT) before IEND";
    pos += 12 + size_t(len);
  }
}

std::string jpeg_problem(const std::vector<uint8_t>& b) {
  // Inside entropy-coded data 0xFF is always followed by 0x00 or a restart marker, so the last
  // start-of-scan (FFDA) and the end-of-image marker (FFD9) cannot be faked by pixel data.
  size_t last_sos = 0, last_eoi = 0;
  for (size_t i = 2; i + 1 < b.size(); ++i) {
    if (b[i] != 0xFF) continue;
    if (b[i + 1] == 0xDA) last_sos = i;
    if (b[i + 1] == 0xD9) last_eoi = i;
  }
  if (last_sos == 0) return "cut short: the file ends before its image data";
  if (last_eoi < last_sos) return "cut short: no end-of-image marker after the last scan";
  return "";
}

}  // namespace

std::string image_file_problem(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return "a folder, not an image file";
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    return "not a regular file (a pipe or device?)";
  std::ifstream in(path, std::ios::binary);
  if (!in.good()) return std::string("cannot be opened (") + std::strerror(errno) + ")";
  const std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), {});
  if (in.bad()) return "cannot be read (I/O error)";
  if (b.empty()) return "the file is empty (0 bytes)";
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (b.size() >= 8 && std::memcmp(b.data(), kPng, 8) == 0) return png_problem(b);
  if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return jpeg_problem(b);
  return "";
}

}  // namespace neraf::io
