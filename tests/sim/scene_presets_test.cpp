// Presets: valid, JSON-equivalent, and sized as documented.
#include <gtest/gtest.h>

#include "neraf/sim/presets.h"
#include "neraf/sim/scene_json.h"
#include "neraf/sim/synthesize.h"
#include "neraf/util/error.h"

namespace neraf::sim {
namespace {

TEST(ScenePresets, AllValidateAndRoundTripThroughJson) {
  for (const auto& name : preset_names()) {
    SCOPED_TRACE(name);
    const Scene s = preset_scene(name);
    EXPECT_NO_THROW(validate_scene(s, "preset " + name));
    EXPECT_EQ(s.name, name);
    const auto j = scene_to_json(s);
    const Scene back = scene_from_json(nlohmann::json::parse(j.dump()), "preset.json");
    EXPECT_EQ(scene_to_json(back), j);
  }
}

TEST(ScenePresets, UnknownPresetListsTheKnownOnes) {
  try {
    preset_scene("castle");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "--preset: unknown preset \"castle\"; choose one of demo, shoebox, furnished");
  }
}

TEST(ScenePresets, DemoIsSmallEnoughToTrainInMinutes) {
  const Scene s = preset_scene("demo");
  const SynthPlan plan = plan_synthesis(s, "soundspaces", 0);
  EXPECT_GE(plan.jobs.size(), 150u);
  EXPECT_LE(plan.jobs.size(), 500u);
  EXPECT_EQ(plan.jobs.size(), 464u);  // 29 free grid points × 4 headings × 4 sources (presets.h)
  EXPECT_EQ(plan.headings_deg, (std::vector<double>{0, 90, 180, 270}));
  EXPECT_EQ(plan.train_cameras.size(), 50u);
  EXPECT_EQ(plan.eval_cameras.size(), 10u);
  EXPECT_GE(s.furniture.size(), 2u);
  EXPECT_LE(s.furniture.size(), 3u);
  int textured = 0;
  for (const auto& [n, m] : s.materials) textured += m.texture.kind != "none";
  EXPECT_GE(textured, 5);
}

TEST(ScenePresets, ShoeboxIsEmptyAndUniform) {
  const Scene s = preset_scene("shoebox");
  EXPECT_TRUE(s.furniture.empty());
  for (const auto& [n, m] : s.materials)
    EXPECT_EQ(m.absorption, s.materials.at("wall").absorption) << n;
  EXPECT_EQ(plan_synthesis(s, "soundspaces", 0).jobs.size(), 80u);
}

TEST(ScenePresets, FurnishedIsLarger) {
  const Scene demo = preset_scene("demo"), f = preset_scene("furnished");
  EXPECT_GT(f.furniture.size(), demo.furniture.size());
  const auto pf = plan_synthesis(f, "soundspaces", 0), pd = plan_synthesis(demo, "soundspaces", 0);
  EXPECT_EQ(pf.jobs.size(), 1112u);  // 139 free grid points × 4 headings × 2 sources (presets.h)
  EXPECT_GT(pf.jobs.size(), 2 * pd.jobs.size());
  EXPECT_GT(pf.train_cameras.size(), pd.train_cameras.size());
}

}  // namespace
}  // namespace neraf::sim
