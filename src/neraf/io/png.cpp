#include "neraf/io/png.h"

// The implementation of stb_image_write is compiled into Debian's libstb.
#include <stb/stb_image_write.h>

#include <cerrno>
#include <cstring>
#include <fstream>

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

}  // namespace neraf::io
