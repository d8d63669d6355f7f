// Timed paths and pose lists (geometry/trajectory.h): interpolation, sampling, and one clear
// error per problem naming the file and the keyframe / pose index.
#include "neraf/geometry/trajectory.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "neraf/util/error.h"

namespace neraf::geometry {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Whether `text` contains `part`; the failure message shows both.
::testing::AssertionResult Contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << text << "\" does not contain \"" << part << "\"";
}

void expect_near(Vec3 a, Vec3 b, double tol = 1e-12) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// ---------------------------------------------------------------------------------------------
// Interpolation

// Three keyframes, a fixed source; the yaw goes 10 → 50 → 350 (the last step turns right by 60°,
// through 0).
json walk() {
  return json::parse(R"({
    "version": 1,
    "source": [1.0, 1.2, 0.9],
    "keyframes": [
      {"time": 0, "mic": [0, 1.5, 0], "yaw": 10},
      {"time": 2, "mic": [2, 1.5, 4], "yaw": 50},
      {"time": 3, "mic": [2, 1.5, 1], "yaw": 350}
    ]
  })");
}

TEST(Trajectory, ParsesKeyframesAndFixedSource) {
  const Trajectory t = parse_trajectory(walk(), "path.json");
  ASSERT_EQ(t.keyframes.size(), 3u);
  EXPECT_FALSE(t.moving_source);
  EXPECT_DOUBLE_EQ(t.duration(), 3.0);
  for (const TimedPose& k : t.keyframes) expect_near(k.source, {1.0, 1.2, 0.9});
  EXPECT_DOUBLE_EQ(t.keyframes[1].time, 2.0);
  expect_near(t.keyframes[1].mic, {2, 1.5, 4});
  EXPECT_DOUBLE_EQ(t.keyframes[2].yaw_deg, 350.0);
}

TEST(Trajectory, InterpolatesPositionsLinearly) {
  const Trajectory t = parse_trajectory(walk(), "path.json");
  // t = 0.5: a quarter of the way from keyframe 0 to 1.
  TimedPose p = t.at(0.5);
  EXPECT_DOUBLE_EQ(p.time, 0.5);
  expect_near(p.mic, {0.5, 1.5, 1.0});
  EXPECT_NEAR(p.yaw_deg, 20.0, 1e-12);
  expect_near(p.source, {1.0, 1.2, 0.9});
  // t = 2.5: half way from keyframe 1 to 2; yaw 50 → 350 is -60°, so 50 - 30 = 20.
  p = t.at(2.5);
  expect_near(p.mic, {2, 1.5, 2.5});
  EXPECT_NEAR(p.yaw_deg, 20.0, 1e-12);
  // t = 2.9: 90 % of -60° = -54° → 356 after wrapping.
  EXPECT_NEAR(t.at(2.9).yaw_deg, 356.0, 1e-9);
  // Exactly at an inner keyframe: that keyframe.
  p = t.at(2.0);
  expect_near(p.mic, {2, 1.5, 4});
  EXPECT_DOUBLE_EQ(p.yaw_deg, 50.0);
}

TEST(Trajectory, ClampsOutsideTheKeyframes) {
  json j = walk();
  j["keyframes"][0]["time"] = 1.0;  // the path starts after t = 0: hold the first pose until then
  const Trajectory t = parse_trajectory(j, "path.json");
  for (double time : {-5.0, 0.0, 0.5, 1.0}) {
    const TimedPose p = t.at(time);
    EXPECT_DOUBLE_EQ(p.time, time);
    expect_near(p.mic, {0, 1.5, 0});
    EXPECT_DOUBLE_EQ(p.yaw_deg, 10.0);
  }
  for (double time : {3.0, 3.5, 1e9, kInf}) {
    const TimedPose p = t.at(time);
    expect_near(p.mic, {2, 1.5, 1});
    EXPECT_DOUBLE_EQ(p.yaw_deg, 350.0);
  }
  expect_near(t.at(kNaN).mic, {0, 1.5, 0});  // NaN: the first pose, never garbage
}

Trajectory two_yaws(double y0, double y1) {
  json j = {{"version", 1},
            {"source", {0, 0, 0}},
            {"keyframes",
             {{{"time", 0}, {"mic", {0, 0, 0}}, {"yaw", y0}},
              {{"time", 1}, {"mic", {0, 0, 0}}, {"yaw", y1}}}}};
  return parse_trajectory(j, "yaw.json");
}

TEST(Trajectory, YawTakesTheShorterArc) {
  Trajectory t = two_yaws(359, 1);  // +2°, through 0
  EXPECT_NEAR(t.at(0.25).yaw_deg, 359.5, 1e-9);
  EXPECT_NEAR(t.at(0.5).yaw_deg, 0.0, 1e-9);
  EXPECT_NEAR(t.at(0.75).yaw_deg, 0.5, 1e-9);
  t = two_yaws(1, 359);  // -2°, through 0
  EXPECT_NEAR(t.at(0.25).yaw_deg, 0.5, 1e-9);
  EXPECT_NEAR(t.at(0.75).yaw_deg, 359.5, 1e-9);
  t = two_yaws(10, 300);  // -70°, not +290°
  EXPECT_NEAR(t.at(0.5).yaw_deg, 335.0, 1e-9);
  t = two_yaws(0, 180);  // a half turn turns towards increasing yaw (left)
  EXPECT_NEAR(t.at(0.5).yaw_deg, 90.0, 1e-9);
  t = two_yaws(180, 0);
  EXPECT_NEAR(t.at(0.5).yaw_deg, 270.0, 1e-9);
  t = two_yaws(0, 360);  // the same heading: no turn at all
  EXPECT_NEAR(t.at(0.5).yaw_deg, 0.0, 1e-9);
}

TEST(Trajectory, YawIsWrappedToZeroTo360) {
  EXPECT_DOUBLE_EQ(two_yaws(-90, 720).keyframes[0].yaw_deg, 270.0);
  EXPECT_DOUBLE_EQ(two_yaws(-90, 720).keyframes[1].yaw_deg, 0.0);
  EXPECT_DOUBLE_EQ(two_yaws(-1e-20, 0).keyframes[0].yaw_deg, 0.0);  // not 360
  EXPECT_NEAR(two_yaws(-90, 720).at(0.5).yaw_deg, 315.0, 1e-9);     // 270 → 360: +90°
}

TEST(Trajectory, MovingSourceIsInterpolated) {
  const json j = json::parse(R"({
    "version": 1,
    "keyframes": [
      {"time": 0, "mic": [1, 1.5, 1], "yaw": 0, "source": [0, 0, 0]},
      {"time": 1, "mic": [1, 1.5, 1], "yaw": 0, "source": [4, 2, 0]}
    ]
  })");
  const Trajectory t = parse_trajectory(j, "path.json");
  EXPECT_TRUE(t.moving_source);
  expect_near(t.at(0.25).source, {1, 0.5, 0});
  expect_near(t.at(0.25).mic, {1, 1.5, 1});
}

TEST(Trajectory, SingleKeyframeIsAStillPose) {
  const json j = json::parse(
      R"({"version": 1, "source": [1, 1, 1], "keyframes": [{"time": 0, "mic": [2, 1.5, 2],
          "yaw": 90}]})");
  const Trajectory t = parse_trajectory(j, "still.json");
  EXPECT_DOUBLE_EQ(t.duration(), 0.0);
  expect_near(t.at(7.0).mic, {2, 1.5, 2});
  EXPECT_EQ(sample_trajectory(t, 10, 0.5).size(), 5u);
}

TEST(Trajectory, EmptyTrajectoryIsAnErrorNotACrash) {
  const Trajectory t;
  EXPECT_THROW(t.at(0), Error);
  EXPECT_THROW(sample_trajectory(t, 10, 1), Error);
  EXPECT_DOUBLE_EQ(t.duration(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Sampling

TEST(SampleTrajectory, CountsAndTimes) {
  const Trajectory t = parse_trajectory(walk(), "path.json");
  auto s = sample_trajectory(t, 4, 1.0);  // 0, 0.25, 0.5, 0.75 (1.0 is not < 1.0)
  ASSERT_EQ(s.size(), 4u);
  for (size_t k = 0; k < s.size(); ++k) EXPECT_DOUBLE_EQ(s[k].time, 0.25 * k);
  expect_near(s[2].mic, t.at(0.5).mic);
  EXPECT_EQ(sample_trajectory(t, 4, 1.01).size(), 5u);
  EXPECT_EQ(sample_trajectory(t, 3, 1.0).size(), 3u);
  EXPECT_EQ(sample_trajectory(t, 10, 0.3).size(), 3u);  // 3/10 == 0.3 exactly: not included
  EXPECT_EQ(sample_trajectory(t, 1000, 0.0005).size(), 1u);
  s = sample_trajectory(t, 20, t.duration());  // the whole path at 20 Hz: 60 poses
  ASSERT_EQ(s.size(), 60u);
  EXPECT_DOUBLE_EQ(s[59].time, 59.0 / 20.0);
  // Past the last keyframe the last pose holds.
  s = sample_trajectory(t, 1, 5.0);
  ASSERT_EQ(s.size(), 5u);
  expect_near(s[4].mic, {2, 1.5, 1});
  EXPECT_DOUBLE_EQ(s[4].time, 4.0);
}

std::string sample_error(double rate, double duration) {
  try {
    sample_trajectory(parse_trajectory(walk(), "path.json"), rate, duration);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SampleTrajectory, BoundsRateAndDuration) {
  EXPECT_EQ(sample_error(1000, 0.01), "");
  for (double rate : {0.0, -1.0, 1000.5, 1e9, kNaN, kInf}) {
    EXPECT_TRUE(Contains(sample_error(rate, 1.0), "at most 1000 Hz")) << rate;
  }
  for (double d : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_TRUE(Contains(sample_error(10, d), "must be a positive number of seconds")) << d;
  }
  EXPECT_TRUE(Contains(sample_error(1000, 1001), "more than the 1000000 allowed"));
}

// ---------------------------------------------------------------------------------------------
// Trajectory validation: one line, naming the file and the keyframe

std::string traj_error(const json& j) {
  try {
    parse_trajectory(j, "path.json");
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("NOT A neraf::Error: ") + e.what();
  }
  return "";
}

std::string traj_error_with(const std::function<void(json&)>& edit) {
  json j = walk();
  edit(j);
  return traj_error(j);
}

TEST(TrajectoryErrors, BaseParses) { EXPECT_EQ(traj_error(walk()), ""); }

TEST(TrajectoryErrors, TopLevel) {
  EXPECT_EQ(traj_error(json::array()), "path.json: must be a JSON object {...}");
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j.erase("version"); }),
                       "path.json: missing \"version\"; add \"version\": 1"));
  EXPECT_EQ(traj_error_with([](json& j) { j["version"] = 2; }),
            "path.json: version: 2: written for a newer neraf (this one reads version 1); "
            "update neraf");
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["version"] = 0; }),
                       "path.json: version: 0 must be 1"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["version"] = 1.5; }),
                       "path.json: version: 1.5 must be 1"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["version"] = "1"; }),
                       "path.json: version: must be 1"));
  EXPECT_EQ(traj_error_with([](json& j) { j["keyframe"] = 1; }),
            "path.json: unknown key \"keyframe\" (known keys: version, description, source, "
            "keyframes); fix the spelling or remove it");
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["description"] = 3; }),
                       "path.json: description: must be a string"));
  EXPECT_EQ(traj_error_with([](json& j) { j["description"] = "a walk"; }), "");
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j.erase("keyframes"); }),
                       "path.json: missing \"keyframes\""));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"] = json::object(); }),
                       "path.json: keyframes: must be a list"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"] = json::array(); }),
                       "path.json: keyframes: is empty; add at least one keyframe"));
}

TEST(TrajectoryErrors, TooManyKeyframesBeforeAllocating) {
  json j = walk();
  json& k = j["keyframes"];
  while (k.size() <= kMaxKeyframes) k.push_back(nullptr);  // invalid ones: the count comes first
  EXPECT_TRUE(Contains(traj_error(j),
                       "path.json: keyframes: 100001 entries, more than the "
                       "100000 allowed"));
}

TEST(TrajectoryErrors, KeyframeFields) {
  EXPECT_EQ(traj_error_with([](json& j) { j["keyframes"][1] = 5; }),
            "path.json: keyframes[1]: must be an object {...}");
  EXPECT_EQ(traj_error_with([](json& j) { j["keyframes"][1]["yaww"] = 5; }),
            "path.json: keyframes[1]: unknown key \"yaww\" (known keys: time, mic, yaw, source); "
            "fix the spelling or remove it");
  for (const char* key : {"time", "mic", "yaw"}) {
    EXPECT_TRUE(Contains(traj_error_with([&](json& j) { j["keyframes"][2].erase(key); }),
                         "path.json: keyframes[2]: missing \"" + std::string(key) + "\"; add it"))
        << key;
  }
}

TEST(TrajectoryErrors, Times) {
  EXPECT_EQ(traj_error_with([](json& j) { j["keyframes"][2]["time"] = 2; }),
            "path.json: keyframes[2].time: 2 is not after keyframes[1].time (2); keyframe times "
            "must strictly increase (sort the keyframes or fix the time)");
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][1]["time"] = -0.5; }),
                       "path.json: keyframes[1].time: -0.5 must be a number of seconds"));
  EXPECT_EQ(traj_error_with([](json& j) { j["keyframes"][1]["time"] = 1.5; }), "");
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][2]["time"] = 1.5; }),
                       "keyframes[2].time: 1.5 is not after keyframes[1].time (2)"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][0]["time"] = -1; }),
                       "path.json: keyframes[0].time: -1 must be"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][1]["time"] = kNaN; }),
                       "path.json: keyframes[1].time: nan must be"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][2]["time"] = 2e6; }),
                       "path.json: keyframes[2].time: 2e+06 must be"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][1]["time"] = "2"; }),
                       "path.json: keyframes[1].time: must be a number of seconds"));
}

TEST(TrajectoryErrors, Positions) {
  const std::string three = "must be [x, y, z]: three numbers in metres";
  EXPECT_EQ(traj_error_with([](json& j) {
              j["keyframes"][1]["mic"] = {1, 2};
            }),
            "path.json: keyframes[1].mic: " + three);
  EXPECT_EQ(traj_error_with([](json& j) {
              j["keyframes"][1]["mic"] = {1, "2", 3};
            }),
            "path.json: keyframes[1].mic: " + three);
  EXPECT_EQ(traj_error_with([](json& j) { j["keyframes"][1]["mic"] = "1,2,3"; }),
            "path.json: keyframes[1].mic: " + three);
  EXPECT_TRUE(Contains(traj_error_with([](json& j) {
                         j["keyframes"][1]["mic"] = {1, kNaN, 3};
                       }),
                       "path.json: keyframes[1].mic: " + three + " (finite"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) {
                         j["keyframes"][2]["mic"] = {kInf, 0, 3};
                       }),
                       "path.json: keyframes[2].mic: " + three + " (finite"));
  EXPECT_EQ(traj_error_with([](json& j) {
              j["keyframes"][2]["mic"] = {1500.0, 0, -2e6};
            }),
            "path.json: keyframes[2].mic: coordinate -2e+06 is beyond ±1e+06 m; positions are "
            "metres in the dataset's frame (not millimetres)");
  EXPECT_EQ(traj_error_with([](json& j) { j["keyframes"][2]["mic"] = {1e6, 0, -1e6}; }), "");
  EXPECT_TRUE(Contains(traj_error_with([](json& j) {
                         j["source"] = {0, 0};
                       }),
                       "path.json: source: " + three));
}

TEST(TrajectoryErrors, Yaw) {
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][1]["yaw"] = "90"; }),
                       "path.json: keyframes[1].yaw: must be a number of degrees"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][1]["yaw"] = kNaN; }),
                       "path.json: keyframes[1].yaw: must be a number of degrees"));
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j["keyframes"][0]["yaw"] = 2e6; }),
                       "path.json: keyframes[0].yaw: 2e+06 is beyond ±1e+06 degrees"));
}

TEST(TrajectoryErrors, Sources) {
  // A top-level source and a per-keyframe one.
  EXPECT_TRUE(Contains(traj_error_with([](json& j) {
                         j["keyframes"][1]["source"] = {1, 1, 1};
                       }),
                       "path.json: keyframes[1].source: the file also has a top-level "
                       "\"source\"; keep one"));
  // No source at all.
  EXPECT_TRUE(Contains(traj_error_with([](json& j) { j.erase("source"); }),
                       "path.json: no source position: add a top-level \"source\""));
  // Per keyframe: every keyframe needs one.
  json j = walk();
  j.erase("source");
  for (json& k : j["keyframes"]) k["source"] = {1, 1, 1};
  EXPECT_EQ(traj_error(j), "");
  j["keyframes"][2].erase("source");
  EXPECT_TRUE(Contains(traj_error(j),
                       "path.json: keyframes[2]: missing \"source\": "
                       "keyframes[0] has one, so every keyframe needs one"));
  j["keyframes"][2]["source"] = {1, 1};
  EXPECT_TRUE(Contains(traj_error(j), "path.json: keyframes[2].source: must be [x, y, z]"));
}

// Whatever the JSON, parsing either succeeds or throws a neraf::Error: every field of the valid
// file replaced by every kind of value.
TEST(TrajectoryErrors, NeverCrashesOnAnyJson) {
  const std::vector<json> odd = {nullptr,
                                 true,
                                 0,
                                 -1,
                                 1e308,
                                 -1e308,
                                 18446744073709551615ull,
                                 kNaN,
                                 "text",
                                 json::array(),
                                 json::object(),
                                 {1, 2, 3, 4},
                                 {nullptr, nullptr, nullptr},
                                 {{"a", 1}},
                                 {{{"time", 0}}}};
  EXPECT_TRUE(Contains(traj_error(nullptr), "path.json: must be a JSON object"));
  for (const json& v : odd) {
    EXPECT_EQ(traj_error(v).rfind("path.json: ", 0), 0u) << v.dump();
    for (const char* key : {"version", "source", "keyframes", "description"}) {
      const std::string e = traj_error_with([&](json& j) { j[key] = v; });
      EXPECT_EQ(e.find("NOT A"), std::string::npos) << key << " = " << v.dump() << ": " << e;
    }
    for (const char* key : {"time", "mic", "yaw", "source"}) {
      const std::string e = traj_error_with([&](json& j) { j["keyframes"][1][key] = v; });
      EXPECT_EQ(e.find("NOT A"), std::string::npos) << key << " = " << v.dump() << ": " << e;
      if (!e.empty()) {
        EXPECT_TRUE(Contains(e, "path.json: keyframes[1]"));
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Files

class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("neraf_trajectory_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  std::filesystem::path dir_;
};

std::string load_error(const std::function<void()>& load) {
  try {
    load();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

using TrajectoryFile = TempDir;

TEST_F(TrajectoryFile, LoadsAndNamesTheFileInErrors) {
  const std::string good = write("walk.json", walk().dump());
  EXPECT_EQ(load_trajectory(good).keyframes.size(), 3u);

  json bad = walk();
  bad["keyframes"][2]["time"] = 1;
  const std::string p = write("bad.json", bad.dump());
  EXPECT_TRUE(Contains(load_error([&] { load_trajectory(p); }),
                       p + ": keyframes[2].time: 1 is not after keyframes[1].time (2)"));

  const std::string missing = (dir_ / "nope.json").string();
  EXPECT_EQ(load_error([&] { load_trajectory(missing); }),
            missing + ": no such file; check the path");
  EXPECT_TRUE(Contains(load_error([&] { load_trajectory(dir_.string()); }), "is a folder"));
  const std::string broken = write("broken.json", "{\"version\": 1, \"keyframes\": [");
  EXPECT_TRUE(
      Contains(load_error([&] { load_trajectory(broken); }), broken + ": not valid JSON (at byte"));
  const std::string huge = write("huge.json", "{\"version\": 1e400}");
  EXPECT_TRUE(Contains(load_error([&] { load_trajectory(huge); }),
                       huge + ": a number in it is too large for a double"));
  const std::string empty = write("empty.json", "");
  EXPECT_TRUE(Contains(load_error([&] { load_trajectory(empty); }), empty + ": not valid JSON"));
}

TEST_F(TrajectoryFile, SwappedFormatsNameTheOtherCommandAndNamesAreEscaped) {
  const std::string path = write("path.json", walk().dump());
  EXPECT_TRUE(Contains(load_error([&] { load_pose_list(path); }),
                       path + ": is a timed path (\"keyframes\"), not a pose list"));
  const std::string list =
      write("list.json", R"({"version": 1, "poses": [{"mic": [1, 1, 1], "source": [2, 1, 1]}]})");
  EXPECT_TRUE(Contains(load_error([&] { load_trajectory(list); }),
                       list + ": is a pose list (\"poses\"), not a timed path"));
  // A NUL in a name would end the one-line message there: it is escaped.
  const std::string nul = write(
      "nul.json",
      R"({"version": 1, "poses": [{"name": "a\u0000b", "mic": [1, 1, 1], "source": [2, 1, 1]}]})");
  const std::string e = load_error([&] { load_pose_list(nul); });
  EXPECT_TRUE(Contains(e, "\"a\\u0000b\" is not a safe file name")) << e;
}

TEST_F(TrajectoryFile, PoseListLoads) {
  const std::string p =
      write("poses.json",
            R"({"version": 1, "source": [1, 1, 1], "poses": [{"mic": [1, 1.5, 1], "yaw": 0}]})");
  EXPECT_EQ(load_pose_list(p).size(), 1u);
  const std::string missing = (dir_ / "nope.json").string();
  EXPECT_EQ(load_error([&] { load_pose_list(missing); }),
            missing + ": no such file; check the path");
  const std::string bad = write("bad.json", R"({"version": 3, "poses": []})");
  EXPECT_TRUE(Contains(load_error([&] { load_pose_list(bad); }),
                       bad + ": version: 3: written for a newer neraf"));
}

// ---------------------------------------------------------------------------------------------
// Pose lists

json poses() {
  return json::parse(R"({
    "version": 1,
    "source": [1.1, 1.2, 0.9],
    "poses": [
      {"mic": [1, 1.5, 1], "yaw": 0},
      {"name": "corner-2.b", "mic": [2, 1.5, 2], "yaw": -90, "source": [3, 1, 2.9]},
      {"mic": [3, 1.5, 1], "yaw": 450}
    ]
  })");
}

std::string pose_error(const json& j) {
  try {
    parse_pose_list(j, "poses.json");
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("NOT A neraf::Error: ") + e.what();
  }
  return "";
}

std::string pose_error_with(const std::function<void(json&)>& edit) {
  json j = poses();
  edit(j);
  return pose_error(j);
}

TEST(PoseList, ParsesWithDefaults) {
  const std::vector<NamedPose> p = parse_pose_list(poses(), "poses.json");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0].name, "pose_0000");
  EXPECT_EQ(p[1].name, "corner-2.b");
  EXPECT_EQ(p[2].name, "pose_0002");          // the index in the file, not a count of unnamed poses
  expect_near(p[0].source, {1.1, 1.2, 0.9});  // the top-level source
  expect_near(p[1].source, {3, 1, 2.9});      // its own source wins
  expect_near(p[2].mic, {3, 1.5, 1});
  EXPECT_DOUBLE_EQ(p[1].yaw_deg, 270.0);  // wrapped to [0, 360)
  EXPECT_DOUBLE_EQ(p[2].yaw_deg, 90.0);
}

TEST(PoseList, DefaultNames) {
  EXPECT_EQ(default_pose_name(0), "pose_0000");
  EXPECT_EQ(default_pose_name(7), "pose_0007");
  EXPECT_EQ(default_pose_name(12345), "pose_12345");
}

TEST(PoseList, NamesMustBeUnique) {
  EXPECT_EQ(pose_error_with([](json& j) { j["poses"][2]["name"] = "corner-2.b"; }),
            "poses.json: poses[2].name: \"corner-2.b\" is already the name of poses[1] (names "
            "become file names, so they must be unique, ignoring case); rename one");
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"][2]["name"] = "CORNER-2.B"; }),
                       "poses.json: poses[2].name: \"CORNER-2.B\" is already the name of "
                       "poses[1]"));
  // An explicit name that an unnamed pose later in the file would get by default.
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"][1]["name"] = "pose_0002"; }),
                       "poses.json: poses[2]: its default name \"pose_0002\" is already the "
                       "name of poses[1]"));
  // ... and one earlier in the file.
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"][1]["name"] = "pose_0000"; }),
                       "poses.json: poses[1].name: \"pose_0000\" is already the name of "
                       "poses[0]"));
}

TEST(PoseList, NamesMustBeSafeFileNames) {
  for (const std::string& bad :
       std::vector<std::string>{"", "../x", "a/b", ".hidden", "..", "a b", "take.tmp-42", "a\\b",
                                "caf\xc3\xa9", "x\ny", std::string(kMaxPoseNameLength + 1, 'a')}) {
    // Quoted as JSON quotes it, so a backslash or newline cannot garble the one-line message.
    std::string quoted;
    for (char c : bad) quoted += c == '\\' ? "\\\\" : c == '\n' ? "\\n" : std::string(1, c);
    EXPECT_TRUE(Contains(pose_error_with([&](json& j) { j["poses"][1]["name"] = bad; }),
                         "poses.json: poses[1].name: \"" + quoted + "\" is not a safe file name"))
        << bad;
  }
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"][1]["name"] = 5; }),
                       "poses.json: poses[1].name: must be a string"));
  for (const std::string& good :
       std::vector<std::string>{"a", "A-b_c.1", "0", "x.", std::string(kMaxPoseNameLength, 'z')}) {
    EXPECT_EQ(pose_error_with([&](json& j) { j["poses"][1]["name"] = good; }), "") << good;
  }
}

TEST(PoseList, FieldsAndLimits) {
  EXPECT_EQ(pose_error(poses()), "");
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j.erase("version"); }),
                       "poses.json: missing \"version\""));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["version"] = 2; }),
                       "poses.json: version: 2: written for a newer neraf"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["pose"] = 2; }),
                       "poses.json: unknown key \"pose\""));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) {
                         j["poses"][2]["src"] = {1, 1, 1};
                       }),
                       "poses.json: poses[2]: unknown key \"src\" (known keys: name, mic, "
                       "source, yaw)"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"][2].erase("mic"); }),
                       "poses.json: poses[2]: missing \"mic\"; add it"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"][2].erase("yaw"); }),
                       "poses.json: poses[2]: missing \"yaw\"; add it"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j.erase("source"); }),
                       "poses.json: poses[0]: missing \"source\"; add it"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) {
                         j["poses"][2]["mic"] = {0, 0, kNaN};
                       }),
                       "poses.json: poses[2].mic: must be [x, y, z]"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) {
                         j["poses"][2]["mic"] = {0, 0, 1e7};
                       }),
                       "poses.json: poses[2].mic: coordinate 1e+07 is beyond"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) {
                         j["poses"][1]["source"] = {0, 0, -1e7};
                       }),
                       "poses.json: poses[1].source: coordinate -1e+07 is beyond"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"][0]["yaw"] = kInf; }),
                       "poses.json: poses[0].yaw: must be a number of degrees"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) { j["poses"] = json::array(); }),
                       "poses.json: poses: is empty; add at least one pose"));
  EXPECT_TRUE(Contains(pose_error_with([](json& j) {
                         j["poses"] = json::array({json::array({1, 2})});
                       }),
                       "poses.json: poses[0]: must be an object"));
  json many = poses();
  while (many["poses"].size() <= kMaxPoses) many["poses"].push_back(nullptr);
  EXPECT_TRUE(Contains(pose_error(many),
                       "poses.json: poses: 100001 entries, more than the 100000 allowed"));
}

TEST(PoseList, NeverCrashesOnAnyJson) {
  const std::vector<json> odd = {
      nullptr,      false,          3, -1e308, kNaN, "x", json::array(), json::object(),
      {1, 2, 3, 4}, {"a", "b", "c"}};
  for (const json& v : odd) {
    EXPECT_EQ(pose_error(v).rfind("poses.json: ", 0), 0u) << v.dump();
    for (const char* key : {"version", "source", "poses", "description"}) {
      const std::string e = pose_error_with([&](json& j) { j[key] = v; });
      EXPECT_EQ(e.find("NOT A"), std::string::npos) << key << " = " << v.dump() << ": " << e;
    }
    for (const char* key : {"name", "mic", "source", "yaw"}) {
      const std::string e = pose_error_with([&](json& j) { j["poses"][1][key] = v; });
      EXPECT_EQ(e.find("NOT A"), std::string::npos) << key << " = " << v.dump() << ": " << e;
      if (!e.empty()) {
        EXPECT_TRUE(Contains(e, "poses.json: poses[1]"));
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The example files of docs/PATH_FORMAT.md

// The `demo` preset (sim/presets.cpp): a 4 × 2.7 × 3.5 m room whose microphone grid (spacing
// 0.55 m, wall margin 0.5 m, height 1.5 m) spans x 0.625..3.375, z 0.65..2.85; the shelf stands
// at x 3.25..3.85, z 0.05..0.95, up to 1.8 m. (Written out here: geometry does not link sim.)
bool inside_demo_grid_box(Vec3 p) {
  const bool in_box = p.x >= 0.625 && p.x <= 3.375 && p.z >= 0.65 && p.z <= 2.85 && p.y == 1.5;
  const bool in_shelf = p.x > 3.15 && p.z < 1.05;  // with 0.1 m clearance
  return in_box && !in_shelf;
}
bool is_demo_source(Vec3 s) {
  const Vec3 sources[] = {{1.1, 1.2, 0.9}, {3.0, 1.0, 2.9}, {2.45, 0.9, 0.75}, {1.75, 1.3, 2.95}};
  for (const Vec3& d : sources) {
    if (norm(s - d) < 1e-12) return true;
  }
  return false;
}

const std::string kExamples = std::string(NERAF_ASSETS_DIR) + "/../examples/paths/";

TEST(ExampleFiles, DemoWalk) {
  const Trajectory t = load_trajectory(kExamples + "demo_walk.json");
  EXPECT_GE(t.duration(), 6.0);
  EXPECT_LE(t.duration(), 10.0);
  EXPECT_DOUBLE_EQ(t.keyframes.front().time, 0.0);
  EXPECT_FALSE(t.moving_source);
  EXPECT_TRUE(is_demo_source(t.keyframes[0].source));
  // Every sampled pose (the keyframes and straight lines between them) stays in the grid's box,
  // and the heading changes along the way.
  double min_yaw = 360, max_yaw = 0;
  for (const TimedPose& p : sample_trajectory(t, 50, t.duration())) {
    EXPECT_TRUE(inside_demo_grid_box(p.mic))
        << "t " << p.time << ": " << p.mic.x << ", " << p.mic.y << ", " << p.mic.z;
    min_yaw = std::min(min_yaw, p.yaw_deg);
    max_yaw = std::max(max_yaw, p.yaw_deg);
  }
  EXPECT_GT(max_yaw - min_yaw, 45.0);
}

TEST(ExampleFiles, DemoPoses) {
  const std::vector<NamedPose> p = load_pose_list(kExamples + "demo_poses.json");
  EXPECT_GE(p.size(), 3u);
  for (const NamedPose& q : p) {
    EXPECT_TRUE(inside_demo_grid_box(q.mic)) << q.name;
    EXPECT_TRUE(is_demo_source(q.source)) << q.name;
  }
}

}  // namespace
}  // namespace neraf::geometry
