// Bad data is never silently accepted: each class of damaged file, written into a tiny dataset in
// the real layout, is an error of `neraf info` (validate_dataset) AND of the loaders training
// uses (RirSet features, ImageSet pixels), naming the file; the legitimate oddities (silence) are
// warnings of both. The clean datasets pass both, so every check here can fail.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>

#include "fixtures.h"
#include "neraf/data/image_set.h"
#include "neraf/data/rir_set.h"
#include "neraf/data/transforms_json.h"
#include "neraf/data/validate.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::data {
namespace {

using testing::NerfstudioScene;
using testing::RafRoom;
using testing::SoundSpacesScene;
using testing::TempDir;

std::string all_text(const std::vector<Problem>& ps) {
  std::string s;
  for (const Problem& p : ps) s += (p.is_error() ? "error: " : "warning: ") + p.to_string() + "\n";
  return s;
}

// What training does with the folder: loads the RIRs with features (building the cache) and the
// images with pixels. "" when both accept it, else the one-line error.
std::string training_error(const std::string& dir, RirLoadOptions ro = {}) {
  ro.progress = false;
  ImageLoadOptions io;
  io.progress = false;
  try {
    const DatasetLayout layout = detect_layout(dir);
    if (layout.has_audio()) load_rir_set(dir, ro);
    if (layout.nerfstudio) load_transforms_json(dir, io);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// info reports an error naming `file_part` and saying `what_part`, and training refuses the data
// with one line naming the file.
void expect_rejected(const std::string& dir, const std::string& file_part,
                     const std::string& what_part) {
  const std::vector<Problem> all = validate_dataset(dir);
  bool found = false;
  for (const Problem& p : all)
    found = found || (p.is_error() && p.file.find(file_part) != std::string::npos &&
                      p.to_string().find(what_part) != std::string::npos && !p.fix.empty());
  EXPECT_TRUE(found) << "no error on " << file_part << " saying '" << what_part << "':\n"
                     << all_text(all);
  const std::string e = training_error(dir);
  EXPECT_NE(e.find(file_part), std::string::npos) << "training: '" << e << "'";
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

// info warns (a problem it counts) and training accepts.
void expect_warned(const std::string& dir, const std::string& file_part,
                   const std::string& what_part) {
  const std::vector<Problem> all = validate_dataset(dir);
  bool found = false, errors = false;
  for (const Problem& p : all) {
    errors = errors || p.is_error();
    found = found || (!p.is_error() && p.file.find(file_part) != std::string::npos &&
                      p.what.find(what_part) != std::string::npos);
  }
  EXPECT_TRUE(found && !errors) << all_text(all);
  EXPECT_EQ(training_error(dir), "");
}

std::vector<float> interleave(const std::vector<std::vector<float>>& ch) {
  std::vector<float> out;
  for (size_t i = 0; i < ch[0].size(); ++i)
    for (const auto& c : ch) out.push_back(c[i]);
  return out;
}

struct Raf {
  TempDir dir;
  RafRoom room;
  Raf() { room.write(dir.path()); }
  std::string wav(int i) const { return dir / ("data/" + RafRoom::id(i) + "/rir.wav"); }
};

struct SoundSpaces {
  TempDir dir;
  SoundSpacesScene scene;
  explicit SoundSpaces(bool magnitudes = false, bool images = false) {
    scene.write(dir.path());
    if (images) NerfstudioScene().write(dir.path());
    if (!magnitudes) return;
    for (const auto& e : scene.entries)
      testing::write_npy(npy(e), {2, 257, 5}, std::vector<float>(2 * 257 * 5, 0.5f));
  }
  std::string wav(size_t i) const { return scene.wav(dir.path(), scene.entries[i]); }
  std::string npy(const SoundSpacesScene::Entry& e) const {
    return dir / ("binaural_magnitudes_sr22050/" + SoundSpacesScene::key(e) + ".npy");
  }
};

TEST(BadData, CleanDatasetsPassInfoAndTraining) {
  Raf raf;
  EXPECT_EQ(all_text(validate_dataset(raf.dir.path())), "");
  EXPECT_EQ(training_error(raf.dir.path()), "");
  SoundSpaces ss(/*magnitudes=*/true, /*images=*/true);
  EXPECT_EQ(all_text(validate_dataset(ss.dir.path())), "");
  EXPECT_EQ(training_error(ss.dir.path()), "");
}

// The issue's example: a header promising 48,000 samples, 5 present (training zero-padded it).
TEST(BadData, TruncatedWav) {
  Raf raf;
  const std::vector<float> five(5, 0.01f);
  testing::write_raw_float_wav(raf.wav(2), 48000, 1, five, /*declared_frames=*/48000);
  expect_rejected(raf.dir.path(), "data/000002/rir.wav", "truncated");

  // Cut in half: every byte after the middle lost (SoundSpaces, binaural).
  SoundSpaces ss;
  std::ifstream in(ss.wav(0), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  in.close();
  std::ofstream(ss.wav(0), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  expect_rejected(ss.dir.path(), "binaural_rirs/0/0_1.wav", "truncated");
}

TEST(BadData, NonFiniteOrHugeSamples) {
  for (const float bad : {std::nanf(""), INFINITY, 1e30f}) {
    Raf raf;
    std::vector<float> x = raf.room.audio(1);
    x[1000] = bad;
    testing::write_raw_float_wav(raf.wav(1), 48000, 1, x);
    expect_rejected(raf.dir.path(), "data/000001/rir.wav", "sample 1000");
  }
  SoundSpaces ss;
  std::vector<std::vector<float>> ch = ss.scene.audio(4);
  ch[1][77] = std::nanf("");
  testing::write_raw_float_wav(ss.wav(4), 44100, 2, interleave(ch));
  expect_rejected(ss.dir.path(), "binaural_rirs/0/2_1.wav", "sample 77 of channel 1");
}

TEST(BadData, AllZeroRirIsAWarningOfInfoAndTraining) {
  Raf raf;
  testing::write_wav(raf.wav(3), 48000, {std::vector<float>(20000, 0.0f)});
  expect_warned(raf.dir.path(), "data/000003/rir.wav", "every sample is zero");
}

TEST(BadData, NanNegativeOrHugeMagnitudes) {
  for (const float bad : {std::nanf(""), -0.5f, 1e30f}) {
    SoundSpaces ss(/*magnitudes=*/true);
    const auto& e = ss.scene.entries[2];
    std::vector<float> m(2 * 257 * 5, 0.5f);
    m[300] = bad;
    testing::write_npy(ss.npy(e), {2, 257, 5}, m);
    expect_rejected(ss.dir.path(), "binaural_magnitudes_sr22050/180/2_3.npy", "magnitude 300");
  }
  // Cut in half (a truncated copy).
  SoundSpaces ss(/*magnitudes=*/true);
  const std::string npy = ss.npy(ss.scene.entries[0]);
  fs::resize_file(npy, fs::file_size(npy) / 2);
  expect_rejected(ss.dir.path(), "binaural_magnitudes_sr22050/0/0_1.npy", "truncated");
}

TEST(BadData, ImplausiblePositions) {
  SoundSpaces ss;
  testing::write_text(
      ss.dir / "metadata/points.txt",
      "0\t1.0\t1.5\t2.0\n1\t1e300\t1.5\t0.25\n2\t2.5\t1.2\t-1.0\n3\t0.0\t1.8\t3.0\n");
  expect_rejected(ss.dir.path(), "metadata/points.txt", "implausible coordinate");

  Raf raf;
  testing::write_text(raf.dir / "data/000001/rx_pos.txt", "1.0,1e300,2.0\n");
  expect_rejected(raf.dir.path(), "data/000001/rx_pos.txt", "implausible");
  Raf raf2;
  testing::write_text(raf2.dir / "data/000002/tx_pos.txt", "0,0.7071,0,0.7071,-2e4,1.5,1.0\n");
  expect_rejected(raf2.dir.path(), "data/000002/tx_pos.txt", "implausible");

  TempDir img;
  NerfstudioScene scene;
  scene.write(img.path());
  std::string json = scene.json_text();
  const std::string first_row = "[[1, 0, 0, 0]";  // frame 0's camera sits at x = 0
  const size_t pos = json.find(first_row);
  ASSERT_NE(pos, std::string::npos) << json;
  json.replace(pos, first_row.size(), "[[1, 0, 0, 1e300]");
  testing::write_text(img / "transforms.json", json);
  expect_rejected(img.path(), "transforms.json", "implausible camera position");
}

TEST(BadData, DuplicateFramesInTransformsJson) {
  TempDir img;
  NerfstudioScene scene;
  scene.names[3] = scene.names[1];  // frames 1 and 3 list the same image
  scene.write(img.path());
  expect_rejected(img.path(), "transforms.json", "lists the same image as frames[1]");
}

// A focal length written as a string is a value of the wrong type, said once, not "no fl_x" for
// every frame.
TEST(BadData, IntrinsicOfTheWrongType) {
  TempDir img;
  NerfstudioScene().write(img.path());
  std::string text = NerfstudioScene().json_text();
  const std::string focal = "\"fl_x\": 10.0";
  text.replace(text.find(focal), focal.size(), "\"fl_x\": \"abc\"");
  testing::write_text(img / "transforms.json", text);
  expect_rejected(img.path(), "transforms.json", "\"fl_x\" is not a number (\"abc\")");
  const std::string all = all_text(validate_dataset(img.path()));
  EXPECT_EQ(all.find("no fl_x"), std::string::npos) << all;
}

// Probe round d, G09: focal lengths of 1e-320 or 2^53 + 1 pixels and a k1 of 1e308 were accepted
// (only "positive and finite" was checked); each is named with its bounds.
TEST(BadData, ImplausibleFocalLengthOrDistortion) {
  const std::pair<const char*, const char*> cases[] = {
      {"\"fl_x\": 1e-320", "fl_x is 9.99989e-321, outside 0.001..1e+06 pixels"},
      {"\"fl_x\": 9007199254740993", "fl_x is 9.0072e+15, outside 0.001..1e+06 pixels"},
      {"\"k1\": 1e308", "distortion k1 is 1e+308, outside ±100"}};
  for (const auto& [value, message] : cases) {
    TempDir img;
    NerfstudioScene().write(img.path());
    std::string text = NerfstudioScene().json_text();
    const std::string key = std::string(value).substr(0, std::string(value).find(':'));
    const size_t at = text.find(key);
    text.replace(at, text.find(',', at) - at, value);
    testing::write_text(img / "transforms.json", text);
    expect_rejected(img.path(), "transforms.json", message);
  }
  Intrinsics k;
  k.fx = k.fy = 10;
  EXPECT_EQ(intrinsics_problem(k), "");
  k.fy = kMaxFocalPixels * 2;
  EXPECT_EQ(intrinsics_problem(k), "fy is 2e+06, outside 0.001..1e+06 pixels");
  k.fy = 10;
  k.p2 = std::nan("");
  EXPECT_EQ(intrinsics_problem(k), "distortion p2 is nan, outside ±100");
}

// G18: a NUL in file_path cut the path (the image before it was read); a control character in a
// frame's path is refused, quoted with JSON escapes.
TEST(BadData, FilePathWithAControlCharacter) {
  TempDir img;
  NerfstudioScene scene;
  scene.write(img.path());
  std::string text = scene.json_text();
  const std::string first = "\"" + scene.names[0] + "\"";
  text.replace(text.find(first), first.size(), "\"" + scene.names[0] + "\\u0000x\"");
  testing::write_text(img / "transforms.json", text);
  expect_rejected(
      img.path(), "transforms.json",
      "frames[0]: file_path \"" + scene.names[0] + "\\u0000x\" holds a control character");
}

// A RIR that is a symlink to a device (or a FIFO) is not a missing file: it is named as what it is.
TEST(BadData, RirThatIsNotARegularFile) {
  Raf raf;
  fs::remove(raf.wav(1));
  fs::create_symlink("/dev/zero", raf.wav(1));
  expect_rejected(raf.dir.path(), "data/000001/rir.wav", "is not a regular file");
  SoundSpaces ss;
  fs::remove(ss.wav(0));
  fs::create_symlink("/dev/zero", ss.wav(0));
  expect_rejected(ss.dir.path(), "binaural_rirs/0/0_1.wav", "is not a regular file");
}

TEST(BadData, PngCutInHalf) {
  TempDir img;
  NerfstudioScene scene;
  scene.write(img.path());
  const std::string png = img / scene.names[2];
  fs::resize_file(png, fs::file_size(png) / 2);
  // The frame's image is named in the message; the problem's file is transforms.json.
  expect_rejected(img.path(), "transforms.json", "eval_0000.png is unusable (cut short");
  EXPECT_NE(training_error(img.path()).find("eval_0000.png"), std::string::npos);
}

// Probe round of 2026-12-04, F22: an index past the range of long (strtol clamped it to
// LONG_MAX) and a fifth column on every row (ignored) were accepted without a word.
TEST(BadData, PointsTxtIndexOutOfRangeOrExtraColumn) {
  SoundSpaces big;
  testing::write_text(big.dir / "metadata/points.txt",
                      "0\t1.0\t1.5\t2.0\n99999999999999999999\t-0.5\t1.5\t0.25\n"
                      "2\t2.5\t1.2\t-1.0\n3\t0.0\t1.8\t3.0\n");
  expect_rejected(big.dir.path(), "metadata/points.txt",
                  "line 2: point index \"99999999999999999999\" is out of range");

  SoundSpaces wide;
  std::string pts;
  for (size_t i = 0; i < wide.scene.points.size(); ++i) {
    const auto& p = wide.scene.points[i];
    pts += std::to_string(i) + "\t" + std::to_string(p[0]) + "\t" + std::to_string(p[1]) + "\t" +
           std::to_string(p[2]) + "\t7\n";
  }
  testing::write_text(wide.dir / "metadata/points.txt", pts);
  expect_rejected(wide.dir.path(), "metadata/points.txt", "line 1: more than 4 columns");
  const std::string all = all_text(validate_dataset(wide.dir.path()));
  EXPECT_NE(all.find("line 4: more than 4 columns"), std::string::npos) << all;
}

// F24: a NUL inside a points.txt line cut the error line ("got '0 1.3" and nothing after it):
// the line is quoted with JSON escapes, whole, and the message goes on to its end.
TEST(BadData, PointsTxtLineWithANulIsQuotedWhole) {
  SoundSpaces ss;
  testing::write_text(ss.dir / "metadata/points.txt",
                      std::string("0\t1.3\0x\t1.5\t2.0\n", 16) +
                          "1\t-0.5\t1.5\t0.25\n2\t2.5\t1.2\t-1.0\n3\t0.0\t1.8\t3.0\n");
  expect_rejected(ss.dir.path(), "metadata/points.txt",
                  R"(line 1: expected 'idx<TAB>x<TAB>y<TAB>z', got "0\t1.3\u0000x\t1.5\t2.0")");
  for (const Problem& p : validate_dataset(ss.dir.path()))
    EXPECT_EQ(p.to_string().find('\0'), std::string::npos) << p.to_string();
}

// A split entry names its wav file: "0/00_1" would be a second entry of 0/0_1.wav (the loader
// builds the name from the numbers), so entries must be written as their numbers print.
TEST(BadData, SoundSpacesSplitEntryWrittenAnotherWay) {
  SoundSpaces ss;
  testing::write_text(ss.dir / "metadata_AudioNeRF/split.json",
                      R"({"train": ["0/0_1", "90/1_2", "0/00_1"], "test": ["180/1_0"]})");
  expect_rejected(ss.dir.path(), "split.json",
                  "train[2] \"0/00_1\" is not \"<rot>/<receiver>_<source>\"");
}

// An entry or id is quoted with JSON escapes: a newline in it would split the one-line error, a
// NUL cut it (and in a RAF id, end the folder's path early).
TEST(BadData, SplitEntriesWithControlCharactersAreQuotedOnOneLine) {
  SoundSpaces ss;
  testing::write_text(ss.dir / "metadata_AudioNeRF/split.json",
                      R"({"train": ["0/0_1\n", "90/1_2"], "test": ["180/1_0"]})");
  expect_rejected(ss.dir.path(), "split.json", R"(train[0] "0/0_1\n" is not)");
  Raf raf;
  testing::write_text(raf.dir / "metadata/data-split.json",
                      R"({"train": [["000001\n", "000000\u0000x", 2]], "test": [[5]]})");
  expect_rejected(raf.dir.path(), "data-split.json", R"(train[0][0] "000001\n" is not an id)");
  const std::string all = all_text(validate_dataset(raf.dir.path()));
  EXPECT_NE(all.find(R"(train[0][1] "000000\u0000x" is not an id)"), std::string::npos) << all;
}

// F22: a source quaternion with a 90° roll was reduced to its yaw without a word. The published
// code uses the yaw alone, so the data stays usable; info and training warn, naming the file.
TEST(BadData, TiltedRafSourceIsAWarning) {
  Raf raf;
  const auto& e = raf.room.entries[2];
  // R = Rz(90°)·Ry(30°): a loudspeaker on its side, facing 30°.
  const geometry::Quaternion q = geometry::multiply(geometry::axis_angle(0, 0, 1, M_PI / 2),
                                                    geometry::axis_angle(0, 1, 0, 30 * M_PI / 180));
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", q.x, q.y, q.z, q.w,
                e.tx[0], e.tx[1], e.tx[2]);
  testing::write_text(raf.dir / "data/000002/tx_pos.txt", buf);
  expect_warned(raf.dir.path(), "data/000002/tx_pos.txt", "tilted 90°");
  RirLoadOptions o;
  o.progress = false;
  o.load_features = false;
  EXPECT_NEAR(load_rir_set(raf.dir.path(), o).rirs[2].raw_yaw_deg, 30.0, 1e-9);
}

// w / h are whole pixels: 1e300 does not fit an int (undefined behaviour before), 12.5 is no size.
TEST(BadData, ImageSizeThatIsNoSize) {
  for (const char* w : {"1e300", "12.5", "-12"}) {
    TempDir img;
    NerfstudioScene scene;
    scene.write(img.path());
    std::string text = scene.json_text();
    const std::string width = "\"w\": 12";
    text.replace(text.find(width), width.size(), std::string("\"w\": ") + w);
    testing::write_text(img / "transforms.json", text);
    expect_rejected(img.path(), "transforms.json", "\"w\" is not a whole number of pixels");
  }
}

bool cache_folder_has_files(const std::string& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(fs::path(dir) / ".neraf_cache", ec)) {
    (void)e;
    return true;
  }
  return false;
}

// One long file would make every RIR padded to it: refused from the headers, before the cache.
TEST(BadData, RirLongerThanAnImpulseResponseCanLast) {
  SoundSpaces ss;
  testing::write_wav(
      ss.wav(1), 44100,
      {std::vector<float>(31 * 44100, 0.01f), std::vector<float>(31 * 44100, 0.01f)});
  expect_rejected(ss.dir.path(), "binaural_rirs/90/1_2.wav", "31.0 s long");
  const std::string e = training_error(ss.dir.path());
  EXPECT_NE(e.find("GB feature cache"), std::string::npos) << e;
  EXPECT_FALSE(cache_folder_has_files(ss.dir.path()));
}

// 121 RIRs of 5 frames and one of 5000 (29 s, under the length limit): padding all of them to it
// makes a 1.25 GB cache, ~100x the features. Refused from the .npy headers, before any work.
TEST(BadData, OneOutlierMustNotPadTheCacheManyTimesOver) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.points.clear();
  for (int i = 0; i < 6; ++i) scene.points.push_back({0.3 * i, 1.5, 0.2 * i});
  scene.entries.clear();
  for (int rot : {0, 90, 180, 270})
    for (int r = 0; r < 6; ++r)
      for (int s = 0; s < 6; ++s)
        if (scene.entries.size() < 122)
          scene.entries.push_back({rot, r, s, 441, scene.entries.size() % 10 != 0});
  scene.write(dir.path());
  for (size_t i = 0; i < scene.entries.size(); ++i) {
    const int64_t t = i == 17 ? 5000 : 5;
    testing::write_npy(
        dir / ("binaural_magnitudes_sr22050/" + SoundSpacesScene::key(scene.entries[i]) + ".npy"),
        {2, 257, t}, std::vector<float>(2 * 257 * t, 0.25f));
  }
  const std::string outlier = SoundSpacesScene::key(scene.entries[17]) + ".npy";
  expect_rejected(dir.path(), outlier, "padded to it");
  EXPECT_NE(training_error(dir.path()).find("1.3 GB"), std::string::npos)
      << training_error(dir.path());
  EXPECT_FALSE(cache_folder_has_files(dir.path()));
}

TEST(BadData, StoppedCacheBuildLeavesNothing) {
  Raf raf;
  std::atomic<bool> stop{true};
  RirLoadOptions o;
  o.stop = &stop;
  const std::string e = training_error(raf.dir.path(), o);
  EXPECT_NE(e.find("interrupted while building the audio feature cache"), std::string::npos) << e;
  // Not even the cache folder the build created (nor a temporary file in it) stays.
  EXPECT_FALSE(fs::exists(raf.dir / ".neraf_cache"));
  stop = false;
  EXPECT_EQ(training_error(raf.dir.path(), o), "");
}

}  // namespace
}  // namespace neraf::data
