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

// Structural check of an image file, for what a decoder lets through: stb_image reads the header
// of a PNG or JPEG cut in half without complaint and decodes the rest as zeros (or noise). A PNG
// must have its signature, chunks inside the file with correct CRCs, and an IEND chunk; a JPEG an
// end-of-image marker after its last scan. Other formats are left to the decoder. Returns "" when
// the file is intact, else what is wrong, without the path ("cut short: no IEND chunk", ...).
std::string image_file_problem(const std::string& path);

}  // namespace neraf::io
