// What commands read back from a run's data.json (infer/run_manifest.h), on manifests damaged the
// ways fuzz/fuzz_data_manifest.cpp tries: every outcome is a value within its range or one
// neraf::Error naming the file, never a library exception or a number wrapped into range.
#include "neraf/infer/run_manifest.h"

#include <gtest/gtest.h>

#include <string>

#include "neraf/util/error.h"

using namespace neraf::infer;
using nlohmann::json;

namespace {

json raf_audio() {
  return json::parse(R"({"layout": "raf", "num_rirs": 6, "num_train": 4, "num_test": 2,
    "hash": "0123456789abcdef", "sample_rate": 48000, "channels": 1, "n_fft": 1024,
    "win_length": 512, "hop_length": 256, "n_freq": 513, "max_len": 60,
    "waveform_length": 15360, "aabb_min": [-0.5, 0.0, -0.5], "aabb_max": [5.0, 2.6, 3.5]})");
}

// The error audio_info_from_manifest throws on `a`, "" when it accepts it.
std::string audio_error(const json& a) {
  try {
    audio_info_from_manifest(a, "run/data.json");
  } catch (const neraf::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RunManifest, AudioEntryReadsBack) {
  const AudioRunInfo info = audio_info_from_manifest(raf_audio(), "run/data.json");
  EXPECT_EQ(info.layout, neraf::data::AudioLayout::raf);
  EXPECT_EQ(info.sample_rate, 48000);
  EXPECT_EQ(info.stft.n_fft, 1024);
  EXPECT_EQ(info.stft.hop_length, 256);
  EXPECT_EQ(info.n_freq, 513);
  EXPECT_EQ(info.aabb.max.y, 2.6);
}

// Numbers that do not fit their field used to be converted first: 1e300 into an int is undefined
// behaviour, 2^32 + 48000 wrapped to 48000 and passed, 48000.5 was cut to 48000.
TEST(RunManifest, AudioNumbersAreCheckedBeforeTheyAreNarrowed) {
  for (const char* bad : {"1e300", "4294975296", "48000.5", "18446744073709551615", "-1"}) {
    json a = raf_audio();
    a["sample_rate"] = json::parse(bad);
    const std::string e = audio_error(a);
    EXPECT_NE(e.find("run/data.json: is damaged (audio.sample_rate is "), std::string::npos)
        << bad << ": " << e;
  }
  json a = raf_audio();
  a["n_freq"] = 1e300;
  EXPECT_NE(audio_error(a).find("audio.n_freq"), std::string::npos) << audio_error(a);
  a = raf_audio();
  a["channels"] = "1";  // a value of another type: incomplete, as a missing key
  EXPECT_EQ(audio_error(a), "run/data.json: the audio manifest is incomplete; re-run neraf train");
  a = raf_audio();
  a.erase("max_len");
  EXPECT_EQ(audio_error(a), "run/data.json: the audio manifest is incomplete; re-run neraf train");
  EXPECT_NE(audio_error(json::array()).find("incomplete"), std::string::npos);
}

// A scene that is not an object (or has a name that is not a string) used to throw the JSON
// library's type_error out of scene_names and find_scene.
TEST(RunManifest, DamagedScenesAreNamedNotThrown) {
  const json m = json::parse(R"({"format": "neraf-run-data-1",
    "scenes": [{"name": "room_a"}, 3, {"name": 7}, {}]})");
  EXPECT_TRUE(is_multiscene(m));
  EXPECT_EQ(scene_names(m), (std::vector<std::string>{"room_a", "?", "?", "?"}));
  EXPECT_EQ(find_scene(m, "room_a", "run"), 0);
  EXPECT_EQ(find_scene(m, "3", "run"), 3);
  EXPECT_THROW(find_scene(m, "room_b", "run"), neraf::Error);
  EXPECT_TRUE(scene_names(json::parse(R"({"scenes": {}})")).empty());
}

TEST(RunManifest, IntrinsicsRoundTripAndRefuseNoSize) {
  neraf::data::Intrinsics k;
  k.fx = 10;
  k.fy = 11;
  k.cx = 6;
  k.cy = 4;
  k.width = 12;
  k.height = 8;
  k.k1 = 0.01;
  const neraf::data::Intrinsics back = intrinsics_from_json(intrinsics_json(k), "data.json");
  EXPECT_EQ(intrinsics_json(back), intrinsics_json(k));
  json j = intrinsics_json(k);
  j["width"] = 1e30;
  EXPECT_THROW(intrinsics_from_json(j, "data.json"), neraf::Error);
}

// Probe round d, G09: a camera file's focal length of 1e-320 or 2^53 + 1 pixels, or a k1 of 1e308,
// rendered a flat picture without a word; the bounds are transforms.json's.
TEST(RunManifest, IntrinsicsOutsidePlausibleBoundsAreRefused) {
  const json good = json::parse(R"({"fx": 10, "fy": 11, "cx": 6, "cy": 4, "width": 12,
                                    "height": 8})");
  EXPECT_NO_THROW(intrinsics_from_json(good, "cam.json: intrinsics"));
  const std::pair<const char*, double> cases[] = {
      {"fx", 1e-320}, {"fy", 9007199254740993.0}, {"k1", 1e308}, {"p2", -101}};
  for (const auto& [key, value] : cases) {
    json j = good;
    j[key] = value;
    try {
      intrinsics_from_json(j, "cam.json: intrinsics");
      ADD_FAILURE() << key << " " << value << " accepted";
    } catch (const neraf::Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("cam.json: intrinsics: ", 0), 0u) << what;
      EXPECT_NE(what.find(std::string(key) + " is "), std::string::npos) << what;
    }
  }
}

// G18: a NUL in data.json's "data" cut the dataset path (the folder before it was read).
TEST(RunManifest, DataPathWithAControlCharacterIsRefused) {
  EXPECT_NO_THROW(check_data_paths(json::parse(R"({"data": "/data/ss"})"), "run/data.json"));
  EXPECT_NO_THROW(check_data_paths(json::parse(R"({"format": "x"})"), "run/data.json"));
  try {
    check_data_paths(json::parse(R"({"data": "/data/ss\u0000junk"})"), "run/data.json");
    ADD_FAILURE() << "a NUL in data was accepted";
  } catch (const neraf::Error& e) {
    EXPECT_STREQ(e.what(),
                 "run/data.json: is damaged (data \"/data/ss\\u0000junk\" holds a control "
                 "character); restore it or re-run neraf train");
  }
  const json multi = json::parse(R"({"scenes": [{"data": "/a"}, {"data": "/b\nc"}]})");
  try {
    check_data_paths(multi, "run/data.json");
    ADD_FAILURE() << "a newline in a scene's data was accepted";
  } catch (const neraf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("scenes[1].data \"/b\\nc\""), std::string::npos)
        << e.what();
  }
}
