// Sizes are bounded before any work: room sides, furniture counts, microphone grids, reflection
// order (validate_scene) and the whole dataset's RIRs and bytes (check_synthesis_size), each an
// error naming the key, the estimate and the limit.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "neraf/sim/presets.h"
#include "neraf/sim/scene_json.h"
#include "neraf/sim/synthesize.h"
#include "neraf/util/error.h"

namespace neraf::sim {
namespace {

using nlohmann::json;

std::string validation_error(const json& j) {
  try {
    scene_from_json(j, "scene.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string size_error(const Scene& s, const std::string& layout, const std::string& flags = "") {
  try {
    check_synthesis_size(s, layout, "preset demo", flags);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(SceneLimits, HugeRoomIsRefusedBeforeAnythingIsPlaced) {
  const std::string e = validation_error(json::parse(R"({"size": [1e9, 3, 4]})"));
  EXPECT_TRUE(contains(e, "scene.json: size:")) << e;
  EXPECT_TRUE(contains(e, "at most 1000 m")) << e;
  EXPECT_EQ(validation_error(json::parse(R"({"size": [1000, 3, 4],
      "microphones": {"grid": {"spacing_m": 5}}})")),
            "");
}

TEST(SceneLimits, TwentyThousandBoxesFailFast) {
  json j = json::parse(R"({"size": [10, 3, 10]})");
  j["furniture"] = json::array();
  for (int i = 0; i < 20000; ++i)
    j["furniture"].push_back({{"center", {5, 0.05, 5}}, {"size", {0.1, 0.1, 0.1}}});
  const auto t0 = std::chrono::steady_clock::now();
  const std::string e = validation_error(j);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(e.rfind("scene.json: furniture: 20000 boxes: at most 1000", 0), 0u) << e;
  EXPECT_LT(s, 5.0);
  json at_limit = json::parse(R"({"size": [10, 3, 10]})");
  at_limit["furniture"] = json::array();
  for (int i = 0; i < 1000; ++i)
    at_limit["furniture"].push_back({{"center", {5, 0.05, 5}}, {"size", {0.1, 0.1, 0.1}}});
  EXPECT_EQ(validation_error(at_limit), "");
}

TEST(SceneLimits, TinyGridSpacingNamesTheCountAndTheLimit) {
  const std::string e = validation_error(
      json::parse(R"({"size": [4, 3, 5], "microphones": {"grid": {"spacing_m": 1e-6}}})"));
  EXPECT_TRUE(contains(e, "microphones.grid.spacing_m: 1e-06 m gives")) << e;
  EXPECT_TRUE(contains(e, "the limit is 1000000")) << e;
}

TEST(SceneLimits, MaxOrderIsTheSimulatorsRange) {
  EXPECT_EQ(validation_error(json::parse(R"({"acoustics": {"max_order": 60}})")), "");
  EXPECT_EQ(validation_error(json::parse(R"({"acoustics": {"max_order": 61}})")),
            "scene.json: acoustics.max_order: must be a whole number in [0, 60]");
}

TEST(SynthesisSize, EstimateCountsRirsAndBytes) {
  const Scene demo = preset_scene("demo");
  const SynthSize z = estimate_synthesis(demo, "soundspaces");
  EXPECT_EQ(z.microphones, 29);
  EXPECT_EQ(z.headings, 4);
  EXPECT_EQ(z.sources, 4);
  EXPECT_EQ(z.rirs, 464);  // the preset's documented count
  EXPECT_EQ(z.channels, 2);
  EXPECT_EQ(z.samples_per_rir, 26460);  // 0.6 s at 44.1 kHz
  EXPECT_DOUBLE_EQ(z.rir_bytes, 464 * (44.0 + 8.0 * 26460));
  EXPECT_EQ(z.images, 60);
  EXPECT_DOUBLE_EQ(z.image_bytes, 60 * 3.0 * 96 * 96);
  const SynthSize raf = estimate_synthesis(demo, "raf");
  EXPECT_EQ(raf.headings, 1);
  EXPECT_EQ(raf.rirs, 29 * 4);
  EXPECT_EQ(raf.channels, 1);
  EXPECT_EQ(size_error(demo, "soundspaces"), "");
}

TEST(SynthesisSize, AMillionRandomMicrophonesIsRefusedWithTheEstimate) {
  Scene s = preset_scene("demo");
  s.microphones.kind = "random";
  s.microphones.random.count = 1000000;
  const std::string e = size_error(s, "raf", "--mic-count");
  EXPECT_EQ(e.rfind("preset demo: the dataset would be 1000000 microphone position(s) x 4 "
                    "source(s) = 4000000 RIRs, about ",
                    0),
            0u)
      << e;
  EXPECT_TRUE(contains(e, "the limits are 250000 RIRs and 64 GB")) << e;
  EXPECT_TRUE(contains(e, "--mic-count")) << e;
  // Under the RIR limit, over the disk limit: 20 s RIRs.
  s.microphones.random.count = 100000;
  s.acoustics.rir_length_s = 20;
  const std::string disk = size_error(s, "soundspaces");
  EXPECT_TRUE(contains(disk, "GB")) << disk;
  s.microphones.random.count = 50;
  EXPECT_EQ(size_error(s, "soundspaces"), "");
}

TEST(SynthesisSize, ImagesCountTowardsTheDisk) {
  Scene s = preset_scene("demo");
  s.cameras.train_count = 100000;
  s.cameras.width = s.cameras.height = 8192;
  const std::string e = size_error(s, "soundspaces");
  EXPECT_TRUE(contains(e, "images ")) << e;
  EXPECT_TRUE(contains(e, "camera images")) << e;
}

TEST(SynthesisSize, SynthesizeChecksBeforeWritingAnything) {
  Scene s = preset_scene("demo");
  s.microphones.kind = "random";
  s.microphones.random.count = 1000000;
  SynthOptions o;
  o.out_dir = ::testing::TempDir() + "/neraf_size_limits_never_created";
  EXPECT_THROW(synthesize(s, o), Error);
  EXPECT_FALSE(std::filesystem::exists(o.out_dir));
}

}  // namespace
}  // namespace neraf::sim
