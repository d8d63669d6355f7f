// The plan drawing puts each thing where the scene has it: known boxes, a microphone and a source
// at the pixels of their world positions, a yawed box rotated, the PNG as drawn.
#include "neraf/sim/plan_drawing.h"

#include <gtest/gtest.h>
#include <stb/stb_image.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "neraf/sim/presets.h"

namespace neraf::sim {
namespace {

namespace fs = std::filesystem;

Box make_box(Vec3 c, Vec3 size, double yaw) {
  Box b;
  b.center = c;
  b.size = size;
  b.yaw_deg = yaw;
  b.material = "wall";
  return b;
}

// 5 × 2.5 × 4 m: a table, a full-height wall, a lintel, a 45° box; one mic, one source.
Scene test_scene() {
  Scene s;
  s.name = "plan_test";
  s.size = {5, 2.5, 4};
  s.furniture = {make_box({1.0, 0.4, 1.0}, {0.8, 0.8, 0.4}, 0),
                 make_box({3.0, 1.25, 1.0}, {0.12, 2.5, 2.0}, 0),
                 make_box({3.0, 2.3, 2.5}, {0.12, 0.4, 1.0}, 0),
                 make_box({4.0, 0.5, 3.0}, {0.8, 1.0, 0.8}, 45)};
  Source src;
  src.position = {1.5, 1.2, 3.0};
  s.sources = {src};
  s.light.position = {2.5, 2.3, 2.0};
  return s;
}

SynthPlan test_plan() {
  SynthPlan p;
  p.layout = "soundspaces";
  p.binaural = true;
  p.headings_deg = {0, 90, 180, 270};
  p.microphones = {{2.0, 1.5, 0.5}};
  return p;
}

// The pixel that contains world point (x, z).
Rgb8 at(const PlanImage& img, double x, double z) {
  return img.pixel(static_cast<int>(std::floor(img.column(x))),
                   static_cast<int>(std::floor(img.row(z))));
}

TEST(PlanDrawing, ThingsAreAtTheirWorldPositions) {
  const Scene s = test_scene();
  const PlanImage img = draw_plan(s, test_plan());
  ASSERT_GT(img.px_per_m, 50);  // 640 px / 5 m = 128 px per metre
  EXPECT_DOUBLE_EQ(img.px_per_m, 128);
  // The table (x 0.6–1.4, z 0.8–1.2): inside furniture, just outside floor.
  EXPECT_EQ(at(img, 1.0, 1.0), kPlanFurniture);
  EXPECT_EQ(at(img, 0.65, 0.85), kPlanFurniture);
  EXPECT_EQ(at(img, 1.0, 1.3), kPlanFloor);
  EXPECT_EQ(at(img, 0.5, 1.0), kPlanFloor);
  // The full-height wall (x 2.94–3.06, z 0–2) is drawn as a wall; the lintel's inside is floor
  // (only its outline is drawn: one can walk and hear below it).
  EXPECT_EQ(at(img, 3.0, 1.0), kPlanWall);
  EXPECT_EQ(at(img, 3.0, 2.5), kPlanFloor);
  // The box at 45°: its centre is furniture; (4.35, 2.65) would be inside it unrotated (a corner
  // of the 0.8 m square) but is outside the rotated one.
  EXPECT_EQ(at(img, 4.0, 3.0), kPlanFurniture);
  EXPECT_EQ(at(img, 4.35, 2.65), kPlanFloor);
  EXPECT_EQ(at(img, 4.5, 3.0), kPlanFurniture);  // 0.5 m along x: inside the diamond (0.566)
  // The microphone dot and the source disc, and the floor beside them.
  EXPECT_EQ(at(img, 2.0, 0.5), kPlanMicrophone);
  EXPECT_EQ(at(img, 2.1, 0.5), kPlanFloor);
  EXPECT_EQ(at(img, 1.5, 3.0), kPlanSource);
  // Outside the room: background.
  EXPECT_EQ(img.pixel(static_cast<int>(img.column(2.5)), static_cast<int>(img.row(-0.2))),
            kPlanBackground);
}

TEST(PlanDrawing, DirectionalSourcesPointWhereTheyFace) {
  Scene s = test_scene();
  s.sources[0].directivity = "cardioid";
  s.sources[0].yaw_deg = 90;  // faces −x: the arrow runs left of the source
  const PlanImage img = draw_plan(s, test_plan());
  EXPECT_EQ(at(img, 1.5 - 12 / img.px_per_m, 3.0), kPlanSource);
  EXPECT_EQ(at(img, 1.5 + 12 / img.px_per_m, 3.0), kPlanFloor);
  s.sources[0].directivity = "omni";
  EXPECT_EQ(at(draw_plan(s, test_plan()), 1.5 - 12 / img.px_per_m, 3.0), kPlanFloor);
}

TEST(PlanDrawing, PngHoldsTheDrawingAndPresetsDraw) {
  const Scene s = test_scene();
  const PlanImage img = draw_plan(s, test_plan());
  const fs::path path =
      fs::temp_directory_path() / ("neraf_plan_" + std::to_string(::getpid()) + ".png");
  write_plan_png(path.string(), img);
  int w = 0, h = 0, c = 0;
  unsigned char* data = stbi_load(path.string().c_str(), &w, &h, &c, 3);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, img.width);
  EXPECT_EQ(h, img.height);
  EXPECT_TRUE(std::equal(img.rgb.begin(), img.rgb.end(), data));
  stbi_image_free(data);
  fs::remove(path);
  // Same input, same picture.
  EXPECT_EQ(draw_plan(s, test_plan()).rgb, img.rgb);
  // Every preset draws (the apartment's 411 microphones and 14 sources included) at a sane size.
  for (const auto& name : preset_names()) {
    SCOPED_TRACE(name);
    const Scene p = preset_scene(name);
    const PlanImage pi = draw_plan(p, plan_synthesis(p, preset_layout(name), 0));
    EXPECT_LE(pi.width, 1400);
    EXPECT_LE(pi.height, 1000);
    EXPECT_EQ(pi.rgb.size(), size_t(pi.width) * pi.height * 3);
  }
}

}  // namespace
}  // namespace neraf::sim
