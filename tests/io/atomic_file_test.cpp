#include "neraf/io/atomic_file.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "neraf/io/json_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::io {
namespace {

class AtomicFileTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("neraf_atomic_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  bool only_file_is(const fs::path& expected) {
    int n = 0;
    for (const auto& entry : fs::directory_iterator(expected.parent_path())) {
      ++n;
      if (entry.path() != expected) return false;
    }
    return n == 1;
  }
  fs::path dir_;
};

TEST_F(AtomicFileTest, WritesThroughTemporaryAndCreatesFolders) {
  const fs::path target = dir_ / "nested" / "out.txt";
  write_text_atomically(target.string(), "hello\n");
  EXPECT_EQ(read_text_file(target.string()), "hello\n");
  EXPECT_TRUE(only_file_is(target));
}

TEST_F(AtomicFileTest, FailedWriteKeepsOldContentAndLeavesNoTemporary) {
  const fs::path target = dir_ / "out.txt";
  write_text_atomically(target.string(), "old");
  EXPECT_THROW(write_atomically(target.string(),
                                [](const std::string& tmp) {
                                  write_text_atomically(tmp, "half");
                                  throw std::runtime_error("interrupted");
                                }),
               std::runtime_error);
  EXPECT_EQ(read_text_file(target.string()), "old");
  EXPECT_TRUE(only_file_is(target));
}

TEST_F(AtomicFileTest, ReadErrorsNameTheFile) {
  const std::string missing = (dir_ / "missing.json").string();
  try {
    read_text_file(missing);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json"), std::string::npos);
  }
  fs::create_directories(dir_);
  const std::string bad = (dir_ / "bad.json").string();
  write_text_atomically(bad, "{\"a\": [1, 2");
  try {
    read_json(bad);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json: not valid JSON"), std::string::npos);
  }
}

// Found by fuzz/fuzz_json_file: nlohmann reports a number beyond a double (1e309) as out_of_range,
// not parse_error; it escaped read_json as a raw nlohmann exception without the file's name.
TEST_F(AtomicFileTest, JsonNumberOverflowIsAnErrorNamingTheFile) {
  fs::create_directories(dir_);
  const std::string huge = (dir_ / "huge.json").string();
  write_text_atomically(huge, "{\"a\": [1, -21e309]}");
  try {
    read_json(huge);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("huge.json: not valid JSON"), std::string::npos);
  }
}

TEST_F(AtomicFileTest, JsonRoundTrip) {
  const std::string path = (dir_ / "x.json").string();
  nlohmann::json value = {{"fs", 22050}, {"channels", {1.5, 2.5}}};
  write_json_atomically(path, value);
  EXPECT_EQ(read_json(path), value);
}

}  // namespace
}  // namespace neraf::io
