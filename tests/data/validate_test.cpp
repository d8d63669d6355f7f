// Dataset validation (`neraf info`): each problem class on a deliberately broken copy of a tiny
// dataset written in the real layout, plus layout detection and the summary numbers.
#include "neraf/data/validate.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fixtures.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::data {
namespace {

using testing::NerfstudioScene;
using testing::RafRoom;
using testing::SoundSpacesScene;
using testing::TempDir;

std::vector<Problem> errors(const std::vector<Problem>& all) {
  std::vector<Problem> e;
  for (const Problem& p : all)
    if (p.is_error()) e.push_back(p);
  return e;
}

// Exactly one error, whose file contains `file_part` and whose text contains `what_part`.
void expect_one_error(const std::string& dir, const std::string& file_part,
                      const std::string& what_part) {
  const auto e = errors(validate_dataset(dir));
  ASSERT_EQ(e.size(), 1u) << (e.empty() ? "no error"
                                        : e[0].to_string() + " ... " + e.back().to_string());
  EXPECT_NE(e[0].to_string().find(file_part), std::string::npos) << e[0].to_string();
  EXPECT_NE(e[0].to_string().find(what_part), std::string::npos) << e[0].to_string();
  EXPECT_FALSE(e[0].fix.empty());
}

struct SoundSpacesWithImages {
  TempDir dir;
  SoundSpacesScene audio;
  NerfstudioScene images;
  SoundSpacesWithImages() {
    audio.write(dir.path());
    images.write(dir.path());
  }
};

TEST(Validate, CleanDatasetsHaveNoErrorsAndASummary) {
  SoundSpacesWithImages ss;
  InspectOptions o;
  o.progress = false;
  o.t60 = [](const io::AudioBuffer& rir, AudioLayout) {
    return std::vector<double>(rir.channels.size(), 0.25);
  };
  const DatasetReport r = inspect_dataset(ss.dir.path(), o);
  EXPECT_EQ(r.num_errors(), 0) << (r.problems.empty() ? "" : r.problems[0].to_string());
  EXPECT_TRUE(r.layout.soundspaces);
  EXPECT_TRUE(r.layout.nerfstudio);
  EXPECT_FALSE(r.layout.raf);
  EXPECT_EQ(r.rirs_train, 5);
  EXPECT_EQ(r.rirs_test, 2);
  EXPECT_EQ(r.images_train, 3);
  EXPECT_EQ(r.images_eval, 1);
  EXPECT_EQ(r.image_width, 12);
  EXPECT_EQ(r.duration_s.count, 7);
  EXPECT_NEAR(r.duration_s.min, 3000.0 / 44100, 1e-12);
  EXPECT_NEAR(r.duration_s.max, 20001.0 / 44100, 1e-12);
  EXPECT_NEAR(r.duration_s.median, 9001.0 / 44100, 1e-12);
  EXPECT_EQ(r.t60_rirs, 7);
  EXPECT_FALSE(r.t60_subsampled);
  EXPECT_EQ(r.t60_s.count, 14);
  EXPECT_DOUBLE_EQ(r.t60_s.median, 0.25);
  // Mic box over all RIRs' mics (points 0-3 mapped to [x, z, -y]).
  EXPECT_DOUBLE_EQ(r.mic_box.min.x, -0.5);
  EXPECT_DOUBLE_EQ(r.mic_box.max.y, 3.0);
  const std::string text = format_report(r);
  EXPECT_NE(text.find("5 train, 2 test"), std::string::npos) << text;
  EXPECT_NE(text.find("SoundSpaces RIRs + nerfstudio images"), std::string::npos) << text;

  TempDir raf;
  RafRoom room;
  room.write(raf.path());
  o.max_sample_reads = 3;  // subset
  const DatasetReport rr = inspect_dataset(raf.path(), o);
  EXPECT_EQ(rr.num_errors(), 0);
  EXPECT_TRUE(rr.layout.raf);
  EXPECT_EQ(rr.rirs_train, 4);
  EXPECT_EQ(rr.rirs_test, 2);
  EXPECT_EQ(rr.t60_rirs, 3);
  EXPECT_TRUE(rr.t60_subsampled);
  EXPECT_NEAR(rr.duration_s.mean, 1.5, 1e-12);
  // Test mic 5 (x = 4.0) lies outside the train-mic box (x up to 3.0): zeroed by normalisation.
  EXPECT_EQ(rr.test_mics_outside, 1);
}

TEST(Validate, MissingWav) {
  SoundSpacesWithImages ss;
  fs::remove(ss.audio.wav(ss.dir.path(), ss.audio.entries[2]));
  expect_one_error(ss.dir.path(), "binaural_rirs/180/2_3.wav", "has no file");
}

TEST(Validate, WrongSampleRate) {
  SoundSpacesWithImages ss;
  testing::write_wav(ss.audio.wav(ss.dir.path(), ss.audio.entries[0]), 48000, ss.audio.audio(0));
  expect_one_error(ss.dir.path(), "binaural_rirs/0/0_1.wav",
                   "sample rate 48000 Hz, expected 44100 Hz");
}

TEST(Validate, WrongChannelCount) {
  SoundSpacesWithImages ss;
  testing::write_wav(ss.audio.wav(ss.dir.path(), ss.audio.entries[1]), 44100,
                     {ss.audio.audio(1)[0]});
  expect_one_error(ss.dir.path(), "binaural_rirs/90/1_2.wav", "1 channel(s), expected 2");
  TempDir raf;
  RafRoom room;
  room.write(raf.path());
  testing::write_wav(raf / "data/000003/rir.wav", 48000, {room.audio(3), room.audio(2)});
  expect_one_error(raf.path(), "data/000003/rir.wav", "2 channel(s), expected 1");
}

TEST(Validate, NaNPoses) {
  SoundSpacesWithImages ss;
  testing::write_text(ss.dir / "metadata/points.txt",
                      "0\t1.0\t1.5\t2.0\n1\tnan\t1.5\t0.25\n2\t2.5\t1.2\t-1.0\n3\t0.0\t1.8\t3.0\n");
  // Point 1 is gone: its line is reported, and every split entry using it too.
  const auto e = errors(validate_dataset(ss.dir.path()));
  ASSERT_GE(e.size(), 2u);
  EXPECT_NE(e[0].to_string().find("points.txt: line 2: point 1 has a NaN"), std::string::npos)
      << e[0].to_string();

  TempDir raf;
  RafRoom room;
  room.write(raf.path());
  testing::write_text(raf / "data/000001/tx_pos.txt", "0,0.7071,0,0.7071,nan,1.5,1.0\n");
  expect_one_error(raf.path(), "data/000001/tx_pos.txt", "NaN");
  room.write(raf.path());
  testing::write_text(raf / "data/000004/rx_pos.txt", "1.0,inf,2.0\n");
  expect_one_error(raf.path(), "data/000004/rx_pos.txt", "NaN, infinite");
  room.write(raf.path());
  testing::write_text(raf / "data/000004/tx_pos.txt", "0,0,0,0,1,1.5,1.0\n");
  expect_one_error(raf.path(), "data/000004/tx_pos.txt", "zero quaternion");
}

TEST(Validate, SplitEntryWithoutFile) {
  TempDir raf;
  RafRoom room;
  room.write(raf.path());
  testing::write_text(raf / "metadata/data-split.json",
                      R"({"train": [[0, 1, 2, 3, 17]], "test": [[4, 5]]})");
  expect_one_error(raf.path(), "data/000017", "has no folder");

  SoundSpacesWithImages ss;
  testing::write_text(ss.dir / "metadata_AudioNeRF/split.json",
                      R"({"train": ["0/0_1", "90/1_2", "180/2_3", "270/3_0", "0/2_1"],
                          "test": ["90/0_3", "180/1_0", "0/3_2"]})");
  expect_one_error(ss.dir.path(), "binaural_rirs/0/3_2.wav", "has no file");
  testing::write_text(ss.dir / "metadata_AudioNeRF/split.json",
                      R"({"train": ["0/0_1", "90/1_2", "180/2_3", "270/3_0", "0/2_1"],
                          "test": ["90/0_3", "180/1_0", "0/3_9"]})");
  expect_one_error(ss.dir.path(), "split.json", "uses point 9");
}

TEST(Validate, DuplicateIds) {
  SoundSpacesWithImages ss;
  testing::write_text(ss.dir / "metadata_AudioNeRF/split.json",
                      R"({"train": ["0/0_1", "90/1_2", "180/2_3", "270/3_0", "0/2_1"],
                          "test": ["90/0_3", "180/1_0", "90/1_2"]})");
  expect_one_error(ss.dir.path(), "split.json", "test[2] \"90/1_2\" is listed twice");
  TempDir raf;
  RafRoom room;
  room.write(raf.path());
  testing::write_text(raf / "metadata/data-split.json",
                      R"({"train": [[0, 1, 2, 3]], "test": [[4, 5, 1]]})");
  expect_one_error(raf.path(), "data-split.json", "\"000001\" is listed twice");
}

TEST(Validate, ImageListedButAbsent) {
  SoundSpacesWithImages ss;
  fs::remove(ss.dir / "images/train_0001.png");
  expect_one_error(ss.dir.path(), "transforms.json", "frames[1] (images/train_0001.png): image");
}

TEST(Validate, ImageSizeDiffersFromIntrinsics) {
  SoundSpacesWithImages ss;
  ss.images.write_image(ss.dir.path(), 3, 12, 9);
  expect_one_error(ss.dir.path(), "transforms.json",
                   "frames[3] (images/train_0002.png): image is 12x9");
}

TEST(Validate, UnreadableAudioAndBadMagnitudeFile) {
  SoundSpacesWithImages ss;
  testing::write_text(ss.audio.wav(ss.dir.path(), ss.audio.entries[4]), "this is not audio");
  expect_one_error(ss.dir.path(), "binaural_rirs/0/2_1.wav",
                   "not an audio file libsndfile can read");

  SoundSpacesWithImages ss2;
  for (size_t i = 0; i < ss2.audio.entries.size(); ++i) {
    const int64_t c = i == 5 ? 1 : 2;  // entry 5 has one channel too few
    testing::write_npy(ss2.dir / ("binaural_magnitudes_sr22050/" +
                                  SoundSpacesScene::key(ss2.audio.entries[i]) + ".npy"),
                       {c, 257, 4}, std::vector<float>(c * 257 * 4, 1.0f));
  }
  expect_one_error(ss2.dir.path(), "binaural_magnitudes_sr22050/90/0_3.npy", "shape [2, 257, T]");
}

TEST(Validate, EmptyWavIsAWarningAndNotAFolderIsAnError) {
  SoundSpacesWithImages ss;
  testing::write_empty_wav(ss.audio.wav(ss.dir.path(), ss.audio.entries[3]), 44100, 2);
  const auto all = validate_dataset(ss.dir.path());
  EXPECT_TRUE(errors(all).empty());
  ASSERT_FALSE(all.empty());
  EXPECT_NE(all[0].to_string().find("holds no samples"), std::string::npos) << all[0].to_string();

  TempDir empty;
  const auto e = errors(validate_dataset(empty.path()));
  ASSERT_EQ(e.size(), 1u);
  EXPECT_NE(e[0].what.find("no known dataset layout"), std::string::npos);
  EXPECT_EQ(errors(validate_dataset(empty / "nope")).size(), 1u);
}

TEST(Validate, LoadersThrowTheSameProblems) {
  SoundSpacesWithImages ss;
  fs::remove(ss.audio.wav(ss.dir.path(), ss.audio.entries[2]));
  fs::remove(ss.audio.wav(ss.dir.path(), ss.audio.entries[3]));
  RirLoadOptions o;
  o.progress = false;
  try {
    load_rir_set(ss.dir.path(), o);
    FAIL();
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("180/2_3.wav"), std::string::npos) << msg;
    EXPECT_NE(msg.find("and 1 more error"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line";
  }
}

}  // namespace
}  // namespace neraf::data
