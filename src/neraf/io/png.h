#pragma once
// 8-bit PNG encoding (stb_image_write, from Debian's libstb) and atomic writing. The one PNG
// writer: the simulator's pictures and every rendered view, map and plot go through it.
#include <cstdint>
#include <string>
#include <vector>

namespace neraf::io {

// pixels: [height, width, channels] row-major, channels 1 (grey), 3 (RGB) or 4 (RGBA).
std::vector<uint8_t> encode_png(int width, int height, int channels, const uint8_t* pixels);

// encode_png, then written atomically; neraf::Error naming `path` when that fails.
void write_png(const std::string& path, int width, int height, int channels, const uint8_t* pixels);

}  // namespace neraf::io
