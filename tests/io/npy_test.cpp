// .npy reader: files written byte-for-byte as numpy.save does (format 1.0 and 2.0), and the
// error cases (wrong dtype, byte order, Fortran order, truncation, not a .npy file).
#include "neraf/io/npy.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::io {
namespace {

class NpyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "neraf_npy_test_XXXXXX").string();
    dir_ = mkdtemp(tmpl.data());
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Header dict padded like numpy (total header a multiple of 64 bytes, ending in '\n').
  std::string write(const std::string& name, const std::string& dict, const void* data,
                    size_t bytes, int major = 1) {
    const size_t prefix = major == 1 ? 10 : 12;
    std::string h = dict;
    const size_t total = prefix + h.size() + 1;
    h += std::string((64 - total % 64) % 64, ' ') + "\n";
    const std::string path = (fs::path(dir_) / name).string();
    std::ofstream out(path, std::ios::binary);
    out.write("\x93NUMPY", 6);
    out.put(static_cast<char>(major));
    out.put(0);
    if (major == 1) {
      const uint16_t n = static_cast<uint16_t>(h.size());
      out.write(reinterpret_cast<const char*>(&n), 2);
    } else {
      const uint32_t n = static_cast<uint32_t>(h.size());
      out.write(reinterpret_cast<const char*>(&n), 4);
    }
    out.write(h.data(), static_cast<std::streamsize>(h.size()));
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
    return path;
  }

  std::string dir_;
};

TEST_F(NpyTest, ReadsFloat32ThreeDimensional) {
  std::vector<float> v(2 * 3 * 4);
  for (size_t i = 0; i < v.size(); ++i) v[i] = 0.5f * i - 3.0f;
  const std::string p =
      write("a.npy", "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3, 4), }", v.data(),
            v.size() * 4);
  const NpyHeader h = read_npy_header(p);
  EXPECT_EQ(h.shape, (std::vector<int64_t>{2, 3, 4}));
  EXPECT_EQ(h.element_size, 4);
  EXPECT_EQ(h.data_offset % 64, 0);
  const NpyArray a = read_npy(p);
  EXPECT_EQ(a.shape, (std::vector<int64_t>{2, 3, 4}));
  EXPECT_EQ(a.data, v);
}

TEST_F(NpyTest, ConvertsFloat64AndReadsVersion2And1D) {
  const std::vector<double> v{1.25, -2.5, 1e-8, 3.0, 7.0};
  const std::string p = write("b.npy", "{'descr': '<f8', 'fortran_order': False, 'shape': (5,), }",
                              v.data(), v.size() * 8, /*major=*/2);
  const NpyArray a = read_npy(p);
  ASSERT_EQ(a.shape, (std::vector<int64_t>{5}));
  for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(a.data[i], static_cast<float>(v[i]));
}

TEST_F(NpyTest, ScalarAndEmptyArrays) {
  const float one = 4.0f;
  const NpyArray s =
      read_npy(write("s.npy", "{'descr': '<f4', 'fortran_order': False, 'shape': (), }", &one, 4));
  EXPECT_TRUE(s.shape.empty());
  ASSERT_EQ(s.data.size(), 1u);
  EXPECT_EQ(s.data[0], 4.0f);
  const NpyArray e = read_npy(
      write("e.npy", "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 0), }", nullptr, 0));
  EXPECT_EQ(e.shape, (std::vector<int64_t>{2, 0}));
  EXPECT_TRUE(e.data.empty());
}

void expect_error_naming(const std::string& path, const std::string& fragment) {
  try {
    read_npy(path);
    FAIL() << "expected an error for " << path;
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(fragment), std::string::npos) << msg;
  }
}

TEST_F(NpyTest, RejectsWhatItCannotReadWithClearErrors) {
  const float v[4] = {1, 2, 3, 4};
  expect_error_naming(
      write("be.npy", "{'descr': '>f4', 'fortran_order': False, 'shape': (4,), }", v, 16), "'>f4'");
  expect_error_naming(
      write("int.npy", "{'descr': '<i4', 'fortran_order': False, 'shape': (4,), }", v, 16),
      "'<i4'");
  expect_error_naming(
      write("f.npy", "{'descr': '<f4', 'fortran_order': True, 'shape': (2, 2), }", v, 16),
      "Fortran order");
  expect_error_naming(
      write("t.npy", "{'descr': '<f4', 'fortran_order': False, 'shape': (8,), }", v, 16),
      "truncated");
  // Found by fuzz/fuzz_npy: shapes whose element count overflows int64 (signed overflow, then a
  // wrapped size of 0 or a negative one that passed the truncation check).
  expect_error_naming(write("huge1.npy",
                            "{'descr': '<f4', 'fortran_order': False, "
                            "'shape': (4611686018427387904, 4), }",
                            v, 16),
                      "too large");
  expect_error_naming(write("huge2.npy",
                            "{'descr': '<f4', 'fortran_order': False, "
                            "'shape': (4611686018427387903,), }",
                            v, 16),
                      "too large");
  expect_error_naming(write("huge3.npy",
                            "{'descr': '<f8', 'fortran_order': False, "
                            "'shape': (3037000500, 3037000500), }",
                            v, 16),
                      "too large");
  expect_error_naming(write("huge4.npy",
                            "{'descr': '<f4', 'fortran_order': False, "
                            "'shape': (46116860, 84273879116860, 0), }",
                            v, 16),
                      "too large");
  const std::string txt = (fs::path(dir_) / "x.npy").string();
  std::ofstream(txt) << "not numpy at all";
  expect_error_naming(txt, "not a NumPy .npy file");
  expect_error_naming((fs::path(dir_) / "missing.npy").string(), "cannot open");
}

}  // namespace
}  // namespace neraf::io
