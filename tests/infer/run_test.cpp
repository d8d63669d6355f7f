// Run folders: checkpoint file names and the latest one, and load_run's errors.
#include "neraf/infer/run.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "neraf/infer/checkpoint.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;
using namespace neraf::infer;

namespace {

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& tag) {
    path = fs::temp_directory_path() /
           ("neraf_infer_run_test_" + tag + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

}  // namespace

TEST(Checkpoint, Names) {
  EXPECT_EQ(fs::path(checkpoint_path("run", 1000)).filename().string(), "step-000001000.pt");
  EXPECT_EQ(checkpoint_step_from_name("run/checkpoints/step-000001000.pt"), 1000);
  EXPECT_EQ(checkpoint_step_from_name("run/checkpoints/step-1000.pt"), -1);
  EXPECT_EQ(checkpoint_step_from_name("step-000001000.pt.tmp-12"), -1);
  TempDir d("names");
  EXPECT_FALSE(latest_checkpoint(d.path.string()).has_value());
  fs::create_directories(checkpoint_dir(d.path.string()));
  for (int64_t s : {5, 120, 40}) std::ofstream(checkpoint_path(d.path.string(), s)) << "x";
  std::ofstream(checkpoint_dir(d.path.string()) + "/step-000000999.pt.tmp-1") << "x";
  EXPECT_EQ(latest_checkpoint(d.path.string()).value(), checkpoint_path(d.path.string(), 120));
}

TEST(Run, LoadRunErrors) {
  TempDir tmp("b");
  EXPECT_THROW(load_run((tmp.path / "nope").string()), neraf::Error);
  EXPECT_THROW(load_run(tmp.path.string()), neraf::Error);  // no config.json
}
