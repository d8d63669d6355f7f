#include "neraf/io/png.h"

#include <gtest/gtest.h>
#include <stb/stb_image.h>
#include <unistd.h>

#include <filesystem>

#include "neraf/util/error.h"

namespace neraf::io {
namespace {

TEST(Png, RoundTripThroughStbImage) {
  std::vector<uint8_t> pixels;
  for (int i = 0; i < 45; ++i) pixels.push_back(static_cast<uint8_t>(i * 5 + 1));
  const auto dir =
      std::filesystem::temp_directory_path() / ("neraf_png_test_" + std::to_string(getpid()));
  const std::string path = (dir / "images" / "a.png").string();  // parent folders are created
  write_png(path, 5, 3, 3, pixels.data());
  int w = 0, h = 0, c = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &c, 0);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, 5);
  EXPECT_EQ(h, 3);
  EXPECT_EQ(c, 3);
  EXPECT_EQ(std::vector<uint8_t>(data, data + 45), pixels);
  stbi_image_free(data);
  EXPECT_EQ(encode_png(5, 3, 3, pixels.data()), encode_png(5, 3, 3, pixels.data()));
  std::filesystem::remove_all(dir);
}

TEST(Png, RejectsEmptyImagesAndOddChannelCounts) {
  const uint8_t px[6] = {};
  EXPECT_THROW(encode_png(0, 1, 3, px), Error);
  EXPECT_THROW(encode_png(1, 1, 2, px), Error);
}

}  // namespace
}  // namespace neraf::io
