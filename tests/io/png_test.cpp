#include "neraf/io/png.h"

#include <gtest/gtest.h>
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

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

std::vector<uint8_t> file_bytes(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
void put_bytes(const std::string& p, const std::vector<uint8_t>& b, size_t n) {
  std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), n);
}

// stb_image reads these without an error; image_file_problem must not.
TEST(ImageFileProblem, FindsPngsAndJpegsCutShortOrDamaged) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("neraf_imgcheck_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::vector<uint8_t> px(64 * 48 * 3);
  for (size_t i = 0; i < px.size(); ++i) px[i] = static_cast<uint8_t>((i * 37) % 251);
  const std::string png = (dir / "a.png").string(), jpg = (dir / "a.jpg").string();
  write_png(png, 64, 48, 3, px.data());
  ASSERT_NE(stbi_write_jpg(jpg.c_str(), 64, 48, 3, px.data(), 90), 0);
  EXPECT_EQ(image_file_problem(png), "");
  EXPECT_EQ(image_file_problem(jpg), "");

  const std::vector<uint8_t> p = file_bytes(png), j = file_bytes(jpg);
  const std::string cut = (dir / "cut.png").string();
  put_bytes(cut, p, p.size() / 2);
  EXPECT_NE(image_file_problem(cut).find("cut short"), std::string::npos)
      << image_file_problem(cut);
  put_bytes(cut, p, p.size() - 12);  // only IEND missing
  EXPECT_NE(image_file_problem(cut).find("IEND"), std::string::npos) << image_file_problem(cut);
  std::vector<uint8_t> flipped = p;
  flipped[p.size() / 2] ^= 0x40;
  put_bytes(cut, flipped, flipped.size());
  EXPECT_NE(image_file_problem(cut).find("CRC"), std::string::npos) << image_file_problem(cut);
  const std::string cutj = (dir / "cut.jpg").string();
  put_bytes(cutj, j, j.size() * 2 / 3);
  EXPECT_NE(image_file_problem(cutj).find("end-of-image"), std::string::npos)
      << image_file_problem(cutj);
  put_bytes(cutj, j, 0);
  EXPECT_NE(image_file_problem(cutj).find("empty"), std::string::npos);
  EXPECT_NE(image_file_problem(dir.string()).find("folder"), std::string::npos);
  EXPECT_NE(image_file_problem((dir / "none.png").string()).find("cannot be opened"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace neraf::io
