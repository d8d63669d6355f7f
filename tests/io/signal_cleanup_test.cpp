#include "neraf/io/signal_cleanup.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::io {
namespace {

class SignalCleanupTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("neraf_signal_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs body in a child process that installed the cleanup handler; returns the wait status.
  static int in_child(const std::function<void()>& body) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      install_signal_cleanup();
      body();
      ::_exit(0);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    return status;
  }

  // A folder with files and a nested folder (and a link out of it, which must not be followed).
  fs::path make_tree(const std::string& name) {
    const fs::path root = dir_ / name;
    fs::create_directories(root / "audio" / "0");
    for (int i = 0; i < 300; ++i)  // more entries than one getdents buffer holds
      std::ofstream(root / "audio" / "0" / ("rir_" + std::to_string(i) + ".wav")) << "x";
    std::ofstream(root / "transforms.json") << "{}";
    fs::create_directory_symlink(dir_ / "keep", root / "link");
    return root;
  }

  fs::path dir_;
};

TEST_F(SignalCleanupTest, SigintDeletesARegisteredFolderAndEndsTheProcessWithTheSignal) {
  const fs::path tree = make_tree("out.tmp-1");
  fs::create_directories(dir_ / "keep");
  std::ofstream(dir_ / "keep" / "precious") << "y";
  const int status = in_child([&] {
    const RemoveOnSignal registered(tree.string());
    ::raise(SIGINT);
  });
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGINT);
  EXPECT_FALSE(fs::exists(tree));
  EXPECT_TRUE(fs::exists(dir_ / "keep" / "precious"));  // the link was removed, not followed
}

TEST_F(SignalCleanupTest, SigtermDeletesARegisteredFile) {
  const fs::path file = dir_ / "model.nrf.tmp-2";
  std::ofstream(file) << "partial";
  const int status = in_child([&] {
    const RemoveOnSignal registered(file.string());
    ::raise(SIGTERM);
  });
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGTERM);
  EXPECT_FALSE(fs::exists(file));
}

TEST_F(SignalCleanupTest, ReleasedAndUnregisteredPathsStay) {
  const fs::path released = make_tree("released");
  const fs::path other = dir_ / "other.txt";
  std::ofstream(other) << "z";
  const int status = in_child([&] {
    { const RemoveOnSignal registered(released.string()); }
    ::raise(SIGINT);
  });
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(fs::exists(released / "audio" / "0" / "rir_299.wav"));
  EXPECT_TRUE(fs::exists(other));
}

TEST_F(SignalCleanupTest, AnInterruptedFolderWriteLeavesNothing) {
  const fs::path target = dir_ / "dataset";
  const int status = in_child([&] {
    write_folder_atomically(target.string(), [](const std::string& tmp) {
      std::ofstream(fs::path(tmp) / "half.json") << "{";
      ::raise(SIGINT);
    });
  });
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(SignalCleanupTest, AnIgnoredSignalStaysIgnored) {
  const fs::path file = dir_ / "kept.tmp-3";
  std::ofstream(file) << "x";
  // Ignored before installing (as under nohup): a SIGHUP neither deletes nor ends the process.
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::signal(SIGHUP, SIG_IGN);
    install_signal_cleanup();
    const RemoveOnSignal registered(file.string());
    ::raise(SIGHUP);
    ::_exit(7);
  }
  int st = 0;
  ::waitpid(pid, &st, 0);
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 7);
  EXPECT_TRUE(fs::exists(file));
}

TEST(RequireCreatable, RefusesWhatCannotBeWrittenBeforeAnyWork) {
  const fs::path dir =
      fs::temp_directory_path() / ("neraf_creatable_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  EXPECT_NO_THROW(require_creatable((dir / "a" / "b" / "out.wav").string()));
  EXPECT_FALSE(fs::exists(dir / "a"));  // checking creates nothing
  EXPECT_TRUE(fs::is_empty(dir));
  EXPECT_THROW(require_creatable((dir / std::string(250, 'n')).string()), Error);
  EXPECT_THROW(require_creatable("/proc/neraf_out.wav"), Error);
  std::ofstream(dir / "file") << "x";
  EXPECT_THROW(require_creatable((dir / "file" / "out.wav").string()), Error);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace neraf::io
