#include "neraf/io/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "neraf/io/folder_lock.h"
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
    EXPECT_NE(std::string(e.what()).find("huge.json: a number in it is too large for a double"),
              std::string::npos)
        << e.what();
    EXPECT_EQ(std::string(e.what()).find("json.exception"), std::string::npos) << e.what();
  }
}

TEST_F(AtomicFileTest, RefusesToReplaceAnythingButARegularFile) {
  fs::create_directories(dir_);
  const fs::path real = dir_ / "real.txt";
  write_text_atomically(real.string(), "keep");
  const fs::path link = dir_ / "link.txt";
  fs::create_symlink(real, link);
  const fs::path fifo = dir_ / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  for (const auto& [path, kind] :
       {std::pair{link, "symbolic link"}, std::pair{fifo, "FIFO"}, std::pair{dir_, "folder"}}) {
    try {
      write_text_atomically(path.string(), "new");
      FAIL() << path;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(kind), std::string::npos) << e.what();
    }
  }
  try {
    read_text_file(fifo.string());  // would block
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is not a regular file"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(fs::status(fifo).type(), fs::file_type::fifo);
  EXPECT_EQ(read_text_file(real.string()), "keep");
  try {
    write_text_atomically("/dev/null", "x");  // as root this would replace the device node
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null: exists and is a device"), std::string::npos)
        << e.what();
  }
}

TEST_F(AtomicFileTest, FolderIsBuiltBesideAndRenamedIntoPlace) {
  const fs::path out = dir_ / "set";
  write_folder_atomically(out.string(), [&](const std::string& tmp) {
    EXPECT_FALSE(fs::exists(out));  // nothing at the target while it is being built
    EXPECT_EQ(fs::path(tmp).parent_path(), dir_);
    write_text_atomically(tmp + "/a.txt", "a");
  });
  EXPECT_EQ(read_text_file((out / "a.txt").string()), "a");
  EXPECT_TRUE(only_file_is(out));
  // A failure leaves the old folder as it was and no temporary folder.
  EXPECT_THROW(write_folder_atomically(
                   out.string(),
                   [](const std::string& tmp) {
                     write_text_atomically(tmp + "/b.txt", "half");
                     throw std::runtime_error("disk full");
                   },
                   FolderWrite::replace),
               std::runtime_error);
  EXPECT_EQ(read_text_file((out / "a.txt").string()), "a");
  EXPECT_TRUE(only_file_is(out));
  // Without `replace` a non-empty folder is refused; with it, it is swapped.
  EXPECT_THROW(write_folder_atomically(out.string(), [](const std::string&) {}), Error);
  write_folder_atomically(
      out.string(), [](const std::string& tmp) { write_text_atomically(tmp + "/c.txt", "c"); },
      FolderWrite::replace);
  EXPECT_FALSE(fs::exists(out / "a.txt"));
  EXPECT_EQ(read_text_file((out / "c.txt").string()), "c");
  EXPECT_TRUE(only_file_is(out));
  // Merge: new files replace their namesakes, the others stay.
  write_text_atomically((out / "keep.txt").string(), "k");
  write_folder_atomically(
      out.string(),
      [](const std::string& tmp) {
        write_text_atomically(tmp + "/c.txt", "c2");
        write_text_atomically(tmp + "/d.txt", "d");
      },
      FolderWrite::merge);
  EXPECT_EQ(read_text_file((out / "c.txt").string()), "c2");
  EXPECT_EQ(read_text_file((out / "d.txt").string()), "d");
  EXPECT_EQ(read_text_file((out / "keep.txt").string()), "k");
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST_F(AtomicFileTest, StaleTemporariesOfDeadProcessesAreRemoved) {
  fs::create_directories(dir_);
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  ASSERT_GT(child, 0);
  ::waitpid(child, nullptr, 0);  // a PID that no process has now
  const std::string dead = std::to_string(child), alive = std::to_string(::getppid());
  write_text_atomically((dir_ / ("ckpt.pt.neraf.tmp-" + dead)).string(), "left by a kill");
  fs::create_directory(dir_ / (".set.neraf.tmp-" + dead));
  write_text_atomically((dir_ / ("model.nrf.neraf.tmp-" + dead + ".tmp-Ab12Cd")).string(), "x");
  write_text_atomically((dir_ / ("other.neraf.tmp-" + alive)).string(), "a live writer's");
  write_text_atomically((dir_ / "plain.txt").string(), "data");
  // A user's names that merely hold ".tmp-<digits>" are not neraf's temporaries (a probe lost
  // such files to an unanchored match).
  for (const std::string& user :
       {"notes.tmp-" + dead + ".txt", "take.tmp-" + dead, "photos.neraf.tmp-" + dead + ".wav"})
    write_text_atomically((dir_ / user).string(), "the user's");
  fs::create_directory(dir_ / ("album.tmp-" + dead));
  EXPECT_EQ(remove_stale_temporaries(dir_.string()), 3);
  EXPECT_TRUE(fs::exists(dir_ / ("other.neraf.tmp-" + alive)));
  EXPECT_TRUE(fs::exists(dir_ / "plain.txt"));
  EXPECT_TRUE(fs::exists(dir_ / ("notes.tmp-" + dead + ".txt")));
  EXPECT_TRUE(fs::exists(dir_ / ("take.tmp-" + dead)));
  EXPECT_TRUE(fs::exists(dir_ / ("photos.neraf.tmp-" + dead + ".wav")));
  EXPECT_TRUE(fs::exists(dir_ / ("album.tmp-" + dead)));
  EXPECT_EQ(remove_stale_temporaries(dir_.string()), 0);
}

TEST_F(AtomicFileTest, FolderLockRefusesASecondWriterAndNamesThePid) {
  {
    const FolderLock first(dir_.string());
    try {
      const FolderLock second(dir_.string());
      FAIL();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("PID " + std::to_string(::getpid())), std::string::npos)
          << e.what();
    }
  }
  EXPECT_NO_THROW(FolderLock again(dir_.string()));  // released with the first
}

TEST_F(AtomicFileTest, JsonKeyGivenTwiceIsAnError) {
  fs::create_directories(dir_);
  const std::string twice = (dir_ / "twice.json").string();
  write_text_atomically(twice, R"({"room": {"size": [4, 3, 5], "size": [9, 9, 9]}})");
  try {
    read_json(twice);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("twice.json: the key \"size\" appears twice"),
              std::string::npos)
        << e.what();
  }
  // The same key in different objects is fine.
  write_text_atomically(twice,
                        R"({"a": {"size": 1}, "b": {"size": 2}, "c": [{"k": 1}, {"k": 2}]})");
  EXPECT_EQ(read_json(twice)["b"]["size"], 2);
}

TEST_F(AtomicFileTest, JsonRoundTrip) {
  const std::string path = (dir_ / "x.json").string();
  nlohmann::json value = {{"fs", 22050}, {"channels", {1.5, 2.5}}};
  write_json_atomically(path, value);
  EXPECT_EQ(read_json(path), value);
}

}  // namespace
}  // namespace neraf::io
