// Presets: valid, JSON-equivalent, and sized as documented.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "neraf/sim/microphones.h"
#include "neraf/sim/occlusion.h"
#include "neraf/sim/presets.h"
#include "neraf/sim/rir_simulator.h"
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
              "--preset: unknown preset \"castle\"; choose one of demo, shoebox, furnished, "
              "occluded, furnished_room, empty_room, small_dead, large_live, apartment, "
              "raf_large");
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

// The counts docs/SCENE_FORMAT.md and presets.h state, from the synth plan (positions only: the
// 20,000-RIR presets are counted without simulating anything).
TEST(ScenePresets, RirCountsAsDocumented) {
  const std::map<std::string, std::pair<std::string, size_t>> expected = {
      {"occluded", {"soundspaces", 800}},     // 50 grid points × 4 headings × 4 sources
      {"furnished_room", {"raf", 600}},       // 300 random microphones × 2 sources
      {"empty_room", {"raf", 600}},           // the same
      {"small_dead", {"soundspaces", 240}},   // 30 × 4 × 2
      {"large_live", {"soundspaces", 864}},   // 108 × 4 × 2
      {"apartment", {"soundspaces", 23016}},  // 411 × 4 × 14
      {"raf_large", {"raf", 20000}}};         // 5,000 × 4
  for (const auto& [name, want] : expected) {
    SCOPED_TRACE(name);
    EXPECT_EQ(preset_layout(name), want.first);
    const Scene s = preset_scene(name);
    const SynthPlan plan = plan_synthesis(s, preset_layout(name), 0);
    EXPECT_EQ(plan.jobs.size(), want.second);
    EXPECT_NO_THROW(check_synthesis_size(s, preset_layout(name), "preset " + name));
  }
  EXPECT_EQ(preset_layout("demo"), "soundspaces");
}

TEST(ScenePresets, LargePresetsAreSoundSpacesAndRafScale) {
  const Scene apt = preset_scene("apartment");
  const SynthPlan ap = plan_synthesis(apt, "soundspaces", 0);
  EXPECT_GE(ap.jobs.size(), 20000u);
  EXPECT_TRUE(ap.binaural);
  EXPECT_EQ(apt.microphones.kind, "grid");
  EXPECT_DOUBLE_EQ(apt.microphones.grid.spacing_m, 0.5);
  EXPECT_EQ(ap.headings_deg, (std::vector<double>{0, 90, 180, 270}));
  EXPECT_GE(apt.sources.size(), 10u);
  // Several rooms: at least 4 full-height interior walls, and furniture besides them.
  int walls = 0;
  for (const Box& b : apt.furniture)
    walls += b.center.y - b.size.y / 2 < 1e-9 && b.center.y + b.size.y / 2 > apt.size.y - 1e-9;
  EXPECT_GE(walls, 4);
  EXPECT_GE(int(apt.furniture.size()) - walls, 8);

  const Scene raf = preset_scene("raf_large");
  const SynthPlan rp = plan_synthesis(raf, "raf", 0);
  EXPECT_GE(rp.jobs.size(), 20000u);
  EXPECT_FALSE(rp.binaural);
  EXPECT_EQ(raf.microphones.kind, "random");
  for (const Source& src : raf.sources) EXPECT_EQ(src.directivity, "cardioid");
}

// occluded: the partition blocks the direct path of a fair share of the pairs, not all; the share
// is what the RIR simulator itself sees (its direct arrival is marked occluded exactly then).
TEST(ScenePresets, OccludedBlocksTheDirectPathForSomePairsOnly) {
  const Scene s = preset_scene("occluded");
  const SynthPlan plan = plan_synthesis(s, "soundspaces", 0);
  const DirectPathCount n = count_blocked_direct_paths(s, plan);
  EXPECT_EQ(n.pairs, 200);
  EXPECT_EQ(n.blocked, 86);  // 43.0 %, as docs/SCENE_FORMAT.md says
  EXPECT_GT(n.share(), 0.25);
  EXPECT_LT(n.share(), 0.6);
  // Every source has pairs of both kinds: listeners on its side and behind the wall.
  RirSimOptions o;
  o.binaural = false;
  o.late_tail = false;
  const RirSimulator sim(s, 48000, nullptr, o);
  for (size_t k = 0; k < s.sources.size(); ++k) {
    int blocked = 0, open = 0;
    for (const Vec3& m : plan.microphones) {
      const bool b = first_blocking_box(s, s.sources[k].position, m) >= 0;
      (b ? blocked : open)++;
      const auto arr = sim.arrivals(s.sources[k], m);
      const auto direct =
          std::find_if(arr.begin(), arr.end(), [](const Arrival& a) { return a.order == 0; });
      ASSERT_NE(direct, arr.end());
      EXPECT_EQ(direct->occluded, b) << "source " << k << " mic " << m.x << "," << m.z;
      // Heard around the wall: at least the 5 dB of the shallowest diffraction at 1 kHz below
      // the free-field 1/r (directivity and air only lower it further).
      if (b) {
        EXPECT_LT(direct->gain[3], std::pow(10.0, -5.0 / 20) / direct->distance_m);
      }
    }
    EXPECT_GE(blocked, 10) << "source " << k;
    EXPECT_GE(open, 10) << "source " << k;
  }
  // The rooms without interior walls block (almost) nothing at listening height.
  EXPECT_EQ(count_blocked_direct_paths(preset_scene("demo"),
                                       plan_synthesis(preset_scene("demo"), "soundspaces", 0))
                .blocked,
            0);
}

// furnished_room and empty_room: the same room but for the furniture, and (because every box is
// below the lowest microphone and camera) the same microphone and camera positions for a seed.
TEST(ScenePresets, FurnishedAndEmptyRoomDifferOnlyInFurniture) {
  const Scene f = preset_scene("furnished_room"), e = preset_scene("empty_room");
  EXPECT_GE(f.furniture.size(), 5u);
  EXPECT_TRUE(e.furniture.empty());
  nlohmann::json jf = scene_to_json(f), je = scene_to_json(e);
  jf.erase("furniture"), je.erase("furniture"), jf.erase("name"), je.erase("name");
  EXPECT_EQ(jf, je);
  for (uint64_t seed : {0, 1, 7}) {
    const SynthPlan pf = plan_synthesis(f, "raf", seed), pe = plan_synthesis(e, "raf", seed);
    ASSERT_EQ(pf.microphones.size(), pe.microphones.size());
    for (size_t i = 0; i < pf.microphones.size(); ++i) {
      EXPECT_EQ(pf.microphones[i].x, pe.microphones[i].x);
      EXPECT_EQ(pf.microphones[i].y, pe.microphones[i].y);
      EXPECT_EQ(pf.microphones[i].z, pe.microphones[i].z);
    }
    ASSERT_EQ(pf.train_cameras.size(), pe.train_cameras.size());
    for (size_t i = 0; i < pf.train_cameras.size(); ++i)
      EXPECT_EQ(pf.train_cameras[i].pose.position.x, pe.train_cameras[i].pose.position.x);
  }
  // The furniture is heard: it blocks some direct paths (the low source behind the table) and
  // shortens the decay (upholstery adds absorption).
  const SynthPlan pf = plan_synthesis(f, "raf", 0);
  EXPECT_GT(count_blocked_direct_paths(f, pf).share(), 0.1);
  RirSimOptions o;
  o.binaural = false;
  const auto tf = RirSimulator(f, 48000, nullptr, o).eyring_t60();
  const auto te = RirSimulator(e, 48000, nullptr, o).eyring_t60();
  EXPECT_LT(tf[3], 0.9 * te[3]);  // 1 kHz
  for (const Source& src : f.sources) EXPECT_EQ(src.directivity, "cardioid");
}

// small_dead, demo and large_live: three sizes and absorptions, in that order of decay time.
TEST(ScenePresets, RoomsOfDifferentSizeAndAbsorption) {
  RirSimOptions o;
  o.binaural = false;
  const auto t60 = [&](const std::string& name) {
    return RirSimulator(preset_scene(name), 48000, nullptr, o).eyring_t60()[3];
  };
  const double dead = t60("small_dead"), demo = t60("demo"), live = t60("large_live");
  EXPECT_LT(dead, 0.2);
  EXPECT_LT(dead * 1.5, demo);
  EXPECT_GT(live, 2 * demo);
  const Scene sd = preset_scene("small_dead"), ll = preset_scene("large_live");
  EXPECT_GT(ll.size.x * ll.size.y * ll.size.z, 20 * sd.size.x * sd.size.y * sd.size.z);
  // Each RIR is long enough for its room's decay to fall by 60 dB at 1 kHz, or close to it.
  EXPECT_GE(sd.acoustics.rir_length_s, 1.5 * dead);
  EXPECT_GE(ll.acoustics.rir_length_s, 0.8 * live);
}

}  // namespace
}  // namespace neraf::sim
