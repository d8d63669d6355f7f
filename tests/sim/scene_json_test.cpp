// Scene JSON: errors name the file and the JSON path, defaults, round trips.
#include "neraf/sim/scene_json.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "neraf/util/error.h"

namespace neraf::sim {
namespace {

using nlohmann::json;

// The message of the neraf::Error that parsing `text` throws ("" when it parses).
std::string error_of(const std::string& text) {
  try {
    scene_from_json(json::parse(text), "scene.json");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// A valid scene that the error cases modify.
json base() {
  return json::parse(R"({
    "size": [4, 3, 5],
    "materials": {"wood": {"albedo": [0.6, 0.4, 0.2]}},
    "furniture": [
      {"center": [1, 0.5, 1], "size": [1, 1, 1]},
      {"center": [3, 0.25, 4], "size": [0.5, 0.5, 0.5], "yaw_deg": 30, "material": "wood"},
      {"center": [2, 0.4, 2.5], "size": [0.8, 0.8, 0.8]}
    ],
    "sources": [{"position": [3, 1.2, 1.0]}]
  })");
}

std::string error_with(const std::function<void(json&)>& edit) {
  json j = base();
  edit(j);
  return error_of(j.dump());
}

TEST(SceneJson, BaseSceneParses) { EXPECT_EQ(error_of(base().dump()), ""); }

TEST(SceneJson, FurnitureSizeErrorNamesThePath) {
  EXPECT_EQ(error_with([](json& j) {
              j["furniture"][2]["size"] = {1, -1, 1};
            }),
            "scene.json: furniture[2].size: must be three positive numbers");
  EXPECT_EQ(error_with([](json& j) { j["furniture"][2]["size"] = "big"; }),
            "scene.json: furniture[2].size: must be three positive numbers");
  EXPECT_EQ(error_with([](json& j) {
              j["furniture"][2]["size"] = {1, 1};
            }),
            "scene.json: furniture[2].size: must be three positive numbers");
}

TEST(SceneJson, TypeErrorsNameThePath) {
  EXPECT_EQ(error_with([](json& j) { j["size"] = "large"; }),
            "scene.json: size: must be three positive numbers");
  EXPECT_EQ(error_with([](json& j) {
              j["size"] = {4, 0, 5};
            }).rfind("scene.json: size: must be three positive numbers", 0),
            0u);
  EXPECT_EQ(error_with([](json& j) { j["cameras"]["width"] = 12.5; }),
            "scene.json: cameras.width: must be a whole number of pixels in [8, 8192]");
  EXPECT_EQ(error_with([](json& j) { j["cameras"]["width"] = 4; }),
            "scene.json: cameras.width: must be a whole number of pixels in [8, 8192]");
  EXPECT_EQ(error_with([](json& j) { j["acoustics"]["rir_length_s"] = -1; }),
            "scene.json: acoustics.rir_length_s: must be a number of seconds in [0.001, 20]");
  // Positive but absurd values are refused when the scene is read (so --dry-run sees them).
  EXPECT_EQ(error_with([](json& j) { j["acoustics"]["rir_length_s"] = 1e-9; }),
            "scene.json: acoustics.rir_length_s: must be a number of seconds in [0.001, 20]");
  EXPECT_EQ(
      error_with([](json& j) { j["acoustics"]["speed_of_sound"] = 1e-9; }),
      "scene.json: acoustics.speed_of_sound: must be a number of m/s in [1, 10000] (air: 343)");
  EXPECT_EQ(error_with([](json& j) { j["sources"][0]["yaw_deg"] = 1e308; }),
            "scene.json: sources[0].yaw_deg: must be a number of degrees in [-1e6, 1e6]");
  EXPECT_EQ(error_with([](json& j) {
              j["furniture"] = json::object();
            }).rfind("scene.json: furniture: must be a list", 0),
            0u);
}

TEST(SceneJson, UnknownKeysAreNamed) {
  const std::string top = error_with([](json& j) { j["sise"] = {1, 2, 3}; });
  EXPECT_NE(top.find("scene.json: unknown key \"sise\""), std::string::npos) << top;
  EXPECT_NE(top.find("size"), std::string::npos) << top;  // lists the known keys

  const std::string nested = error_with([](json& j) { j["furniture"][1]["colour"] = "red"; });
  EXPECT_NE(nested.find("scene.json: furniture[1]: unknown key \"colour\""), std::string::npos)
      << nested;

  const std::string mat = error_with([](json& j) { j["materials"]["wood"]["absorb"] = 0.1; });
  EXPECT_NE(mat.find("scene.json: materials.wood: unknown key \"absorb\""), std::string::npos)
      << mat;

  const std::string two = error_with([](json& j) {
    j["microphones"]["grid"]["spaceing"] = 1;
    j["microphones"]["grid"]["hight"] = 1;
  });
  EXPECT_NE(two.find("microphones.grid: unknown keys \"hight\", \"spaceing\""), std::string::npos)
      << two;
}

TEST(SceneJson, AbsorptionMustBeSevenValuesBelowOne) {
  const std::string one = error_with(
      [](json& j) { j["materials"]["wood"]["absorption"] = {0.1, 0.1, 0.1, 1.0, 0.1, 0.1, 0.1}; });
  EXPECT_EQ(one.rfind("scene.json: materials.wood.absorption: must be 7 numbers in [0, 1)", 0), 0u)
      << one;
  const std::string six = error_with(
      [](json& j) { j["materials"]["wood"]["absorption"] = {0.1, 0.1, 0.1, 0.1, 0.1, 0.1}; });
  EXPECT_EQ(six.rfind("scene.json: materials.wood.absorption: must be 7 numbers in [0, 1)", 0), 0u)
      << six;
  const std::string neg = error_with(
      [](json& j) { j["materials"]["wood"]["absorption"] = {-0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1}; });
  EXPECT_EQ(neg.rfind("scene.json: materials.wood.absorption:", 0), 0u) << neg;
}

TEST(SceneJson, UnknownMaterialNames) {
  const std::string f = error_with([](json& j) { j["furniture"][0]["material"] = "marble"; });
  EXPECT_EQ(f.rfind("scene.json: furniture[0].material: unknown material \"marble\"", 0), 0u) << f;
  const std::string s = error_with([](json& j) { j["surfaces"]["wall_z1"] = "glass"; });
  EXPECT_EQ(s.rfind("scene.json: surfaces.wall_z1: unknown material \"glass\"", 0), 0u) << s;
}

TEST(SceneJson, TexturesAreChecked) {
  const std::string k = error_with([](json& j) {
    j["materials"]["wood"]["texture"] = {{"kind", "plaid"}};
  });
  EXPECT_EQ(k.rfind("scene.json: materials.wood.texture.kind: unknown texture \"plaid\"", 0), 0u)
      << k;
  const std::string c = error_with([](json& j) {
    j["materials"]["wood"]["texture"] = {{"kind", "noise"}, {"contrast", 2}};
  });
  EXPECT_EQ(c, "scene.json: materials.wood.texture.contrast: must be a number in [0, 1]");
  // The string shorthand works.
  EXPECT_EQ(error_with([](json& j) { j["materials"]["wood"]["texture"] = "checker"; }), "");
  // Probe round d, G17: a texture cell of 1e-320 m was accepted (noise at any image size).
  for (const double scale : {1e-320, 1e-4, 2e3}) {
    const std::string t = error_with([&](json& j) {
      j["materials"]["wood"]["texture"] = {{"kind", "checker"}, {"scale_m", scale}};
    });
    EXPECT_EQ(t,
              "scene.json: materials.wood.texture.scale_m: must be a number of metres in "
              "[0.001, 1000]")
        << scale;
  }
  EXPECT_EQ(error_with([](json& j) {
              j["materials"]["wood"]["texture"] = {{"kind", "checker"}, {"scale_m", 0.06}};
            }),
            "");
  // A long unknown kind is quoted cut, so the error stays a short line (G12).
  const std::string long_kind = error_with([](json& j) {
    j["materials"]["wood"]["texture"] = {{"kind", std::string(100000, 'q')}};
  });
  EXPECT_LT(long_kind.size(), 500u);
  EXPECT_NE(long_kind.find("(100000 characters)"), std::string::npos) << long_kind.substr(0, 500);
}

// G17: light.intensity 1e308 was accepted (every lit pixel white); the light terms are bounded.
TEST(SceneJson, LightTermsAreBounded) {
  for (const char* key : {"intensity", "ambient"}) {
    for (const double v : {1e308, 101.0, -1.0}) {
      const std::string e = error_with([&](json& j) { j["light"][key] = v; });
      EXPECT_EQ(e, std::string("scene.json: light.") + key + ": must be a number in [0, 100]")
          << key << " " << v;
    }
    EXPECT_EQ(error_with([&](json& j) { j["light"][key] = 100; }), "") << key;
    EXPECT_EQ(error_with([&](json& j) { j["light"][key] = 0; }), "") << key;
  }
}

TEST(SceneJson, BoxesMustStayInsideTheRoom) {
  const std::string e = error_with([](json& j) { j["furniture"][1]["center"] = {3.9, 0.25, 4}; });
  EXPECT_EQ(e.rfind("scene.json: furniture[1]: the box", 0), 0u) << e;
  EXPECT_NE(e.find("reaches outside the room"), std::string::npos) << e;
  // A 45° yaw widens the footprint: a 1 m cube centred 0.6 m from a wall no longer fits.
  const std::string yaw = error_with([](json& j) {
    j["furniture"][0] = {{"center", {0.6, 0.5, 1}}, {"size", {1, 1, 1}}, {"yaw_deg", 45}};
  });
  EXPECT_EQ(yaw.rfind("scene.json: furniture[0]: the box", 0), 0u) << yaw;
  EXPECT_EQ(error_with([](json& j) {
              j["furniture"][0] = {{"center", {0.6, 0.5, 1}}, {"size", {1, 1, 1}}};
            }),
            "");
}

TEST(SceneJson, SourcesAndMicrophonesMustBeInFreeSpace) {
  const std::string in_box = error_with([](json& j) { j["sources"][0]["position"] = {1, 0.5, 1}; });
  EXPECT_EQ(in_box.rfind("scene.json: sources[0].position: [1, 0.5, 1] is inside furniture[0]", 0),
            0u)
      << in_box;
  const std::string outside = error_with([](json& j) {
    j["sources"].push_back({{"position", {5, 1, 1}}});
  });
  EXPECT_EQ(outside.rfind("scene.json: sources[1].position: [5, 1, 1] is outside the room", 0), 0u)
      << outside;
  const std::string dir = error_with([](json& j) { j["sources"][0]["directivity"] = "figure8"; });
  EXPECT_EQ(dir.rfind("scene.json: sources[0].directivity: unknown directivity", 0), 0u) << dir;

  const std::string mic = error_with([](json& j) { j["microphones"]["grid"]["height_m"] = 3.5; });
  EXPECT_EQ(mic.rfind("scene.json: microphones.grid.height_m: must be inside the room height", 0),
            0u)
      << mic;
  const std::string heading = error_with([](json& j) {
    j["microphones"]["grid"]["headings_deg"] = {0, 45.5};
  });
  EXPECT_EQ(heading.rfind("scene.json: microphones.grid.headings_deg: must be a non-empty list", 0),
            0u)
      << heading;
  const std::string rnd = error_with([](json& j) {
    j["microphones"]["kind"] = "random";
    j["microphones"]["random"]["max_height_m"] = 9;
  });
  EXPECT_EQ(rnd.rfind("scene.json: microphones.random.min_height_m:", 0), 0u) << rnd;
  // Every grid point inside furniture: a 4 × 5 m floor fully covered by one tall box.
  const std::string covered = error_with([](json& j) {
    j["furniture"] = {{{"center", {2, 1.0, 2.5}}, {"size", {4, 2, 5}}}};
    j["sources"][0]["position"] = {2, 2.5, 2.5};
  });
  EXPECT_EQ(covered.rfind("scene.json: microphones.grid: no grid point is in free space", 0), 0u)
      << covered;

  const std::string light = error_with([](json& j) { j["light"]["position"] = {2, 3.5, 2}; });
  EXPECT_EQ(light.rfind("scene.json: light.position: [2, 3.5, 2] is outside the room", 0), 0u)
      << light;
}

// Found by fuzz/fuzz_scene_json: the microphone grid was built before its size was checked, so a
// tiny spacing overflowed the int point count (undefined behaviour) or made billions of points.
TEST(SceneJson, TinyGridSpacingIsAnErrorNotBillionsOfPoints) {
  for (const double spacing : {1e-9, 5e-4, 1e-300}) {
    const std::string e =
        error_with([&](json& j) { j["microphones"]["grid"]["spacing_m"] = spacing; });
    EXPECT_EQ(e.rfind("scene.json: microphones.grid.spacing_m: ", 0), 0u) << e;
    EXPECT_NE(e.find(" grid points in a 4 x 5 m room (the limit is 1000000)"), std::string::npos)
        << e;
    EXPECT_NE(e.find("use a larger spacing"), std::string::npos) << e;
  }
  // A huge room is refused by its size before the grid is counted.
  const std::string huge_room = error_with([](json& j) { j["size"] = {1e7, 3, 1e7}; });
  EXPECT_EQ(
      huge_room.rfind("scene.json: size: [1e+07, 3, 1e+07] m: each side must be at most 1000", 0),
      0u)
      << huge_room;
}

TEST(SceneJson, DefaultsFillEverything) {
  const Scene s = scene_from_json(json::object(), "empty.json");
  EXPECT_DOUBLE_EQ(s.size.x, 5);
  EXPECT_DOUBLE_EQ(s.size.y, 3);
  EXPECT_DOUBLE_EQ(s.size.z, 4);
  ASSERT_EQ(s.sources.size(), 1u);
  EXPECT_DOUBLE_EQ(s.sources[0].position.x, 2.5);
  EXPECT_DOUBLE_EQ(s.sources[0].position.y, 1.2);
  EXPECT_DOUBLE_EQ(s.sources[0].position.z, 2.0);
  EXPECT_DOUBLE_EQ(s.light.position.y, 3 - 0.15);  // just below the ceiling centre
  EXPECT_EQ(s.materials.count("wall"), 1u);
  EXPECT_EQ(s.microphones.kind, "grid");
  EXPECT_EQ(s.cameras.train_count, Cameras{}.train_count);
  // A partly specified material takes the Material{} defaults for the rest.
  const Scene w =
      scene_from_json(json::parse(R"({"materials": {"wall": {"albedo": [1, 0, 0]}}})"), "w.json");
  EXPECT_EQ(w.materials.at("wall").absorption, Material{}.absorption);
  EXPECT_DOUBLE_EQ(w.materials.at("wall").albedo.x, 1.0);
}

TEST(SceneJson, RoundTripIsExact) {
  json j = base();
  j["name"] = "round trip";
  j["materials"]["wood"]["absorption"] = {0.01, 0.123456789012345, 0.3, 0.4, 0.5, 0.6, 0.7};
  j["materials"]["wood"]["texture"] = {{"kind", "noise"}, {"scale_m", 0.1234}, {"contrast", 0.7}};
  j["sources"].push_back(
      {{"position", {0.5, 2.0, 4.5}}, {"yaw_deg", 123.25}, {"directivity", "cardioid"}});
  j["microphones"] = {{"kind", "random"}, {"random", {{"count", 17}, {"headings_deg", {0, 180}}}}};
  j["cameras"] = {{"train_count", 7}, {"width", 33}, {"fov_deg", 75.5}};
  j["light"] = {{"position", {1.1, 2.2, 3.3}}, {"intensity", 0.7}};
  j["acoustics"] = {{"max_order", 3}, {"rir_length_s", 0.25}};
  const Scene a = scene_from_json(j, "a.json");
  const json ja = scene_to_json(a);
  // Through text, as the written scene.json is read back.
  const Scene b = scene_from_json(json::parse(ja.dump(2)), "b.json");
  EXPECT_EQ(scene_to_json(b), ja);
  EXPECT_EQ(b.name, "round trip");
  EXPECT_EQ(b.materials.at("wood").absorption[1], 0.123456789012345);
  EXPECT_EQ(b.sources[1].yaw_deg, 123.25);
  EXPECT_EQ(b.sources[1].directivity, "cardioid");
  EXPECT_EQ(b.microphones.random.count, 17);
  EXPECT_EQ(b.microphones.random.headings_deg, (std::vector<double>{0, 180}));
  EXPECT_EQ(b.cameras.width, 33);
  EXPECT_EQ(b.furniture[1].yaw_deg, 30);
  EXPECT_EQ(b.light.position.z, 3.3);
  EXPECT_EQ(b.acoustics.max_order, 3);
}

TEST(SceneJson, LoadSceneNamesTheFile) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("neraf_scene_json_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string bad = (dir / "bad.json").string();
  std::ofstream(bad) << "{\"size\": [1, 2,";
  try {
    load_scene(bad);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(bad + ": not valid JSON", 0), 0u) << e.what();
  }
  const std::string wrong = (dir / "wrong.json").string();
  std::ofstream(wrong) << R"({"furniture": [{"center": [1, 1, 1], "size": [1, 0, 1]}]})";
  try {
    load_scene(wrong);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), wrong + ": furniture[0].size: must be three positive numbers");
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace neraf::sim
