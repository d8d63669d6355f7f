#pragma once
// A top-down plan of a scene as an RGB picture (`neraf synth` writes DATASET/plan.png; `neraf synth
// --plan-only FILE.png` draws it without synthesising): the room, interior walls (full-height
// boxes), furniture, boxes above head height (door lintels, outlined), microphones, sources with
// the facing direction of directional ones, cameras, metre axes, a title with the counts and a
// legend.
//
// Seen from above (+y): x runs to the right, z downwards, so the picture is the world's x-z plane
// with the usual image orientation. Drawn here rather than with render/'s Canvas because sim/ does
// not link LibTorch and the plan needs words (stb_easy_font's ASCII font, no font files).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "neraf/sim/scene.h"
#include "neraf/sim/synthesize.h"

namespace neraf::sim {

using Rgb8 = std::array<uint8_t, 3>;

// The fill colours, public so tests can look for them.
constexpr Rgb8 kPlanBackground{255, 255, 255};
constexpr Rgb8 kPlanFloor{238, 233, 220};
constexpr Rgb8 kPlanFurniture{205, 170, 120};
constexpr Rgb8 kPlanWall{70, 72, 82};
constexpr Rgb8 kPlanOverhead{150, 150, 160};  // outline of a box above head height
constexpr Rgb8 kPlanMicrophone{30, 90, 200};
constexpr Rgb8 kPlanSource{215, 40, 40};
constexpr Rgb8 kPlanTrainCamera{30, 150, 60};
constexpr Rgb8 kPlanEvalCamera{150, 60, 170};

// A box counts as an interior wall when it spans the room's height (within this), and as
// "overhead" (drawn as an outline: sound and sight pass below it) when its bottom is higher than
// this above the floor.
constexpr double kPlanFullHeightTolM = 0.05;
constexpr double kPlanOverheadBottomM = 1.8;

struct PlanImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // [height][width][3], row-major
  // World (x, z) in metres → continuous pixel coordinates; pixel (c, r) covers [c, c+1)×[r, r+1).
  double left_px = 0, top_px = 0, px_per_m = 0;
  double column(double x) const { return left_px + x * px_per_m; }
  double row(double z) const { return top_px + z * px_per_m; }
  Rgb8 pixel(int c, int r) const;
};

// The plan of `scene` with the microphones and cameras of `plan` (from plan_synthesis, so the
// same seed and layout as the dataset). Deterministic.
PlanImage draw_plan(const Scene& scene, const SynthPlan& plan);

// draw_plan as a PNG, written atomically (neraf::Error naming `path` on failure).
void write_plan_png(const std::string& path, const PlanImage& image);

}  // namespace neraf::sim
