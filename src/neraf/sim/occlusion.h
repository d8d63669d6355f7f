#pragma once
// Which source-microphone pairs of a scene have their direct path blocked by a box (an interior
// wall or furniture): the same straight-segment test the RIR simulator makes on the direct path
// (rir_simulator.h, step 3), so `neraf synth --dry-run` and docs/SCENE_FORMAT.md can say how much
// of a dataset is heard around an obstacle.
#include <cstdint>

#include "neraf/sim/scene.h"
#include "neraf/sim/synthesize.h"

namespace neraf::sim {

// Index of the first furniture box the segment a→b crosses (or that contains an end), or -1.
int first_blocking_box(const Scene& scene, const Vec3& a, const Vec3& b);

struct DirectPathCount {
  int64_t pairs = 0;    // distinct (microphone position, source) pairs of the plan
  int64_t blocked = 0;  // of which the direct segment crosses a box
  double share() const { return pairs ? double(blocked) / double(pairs) : 0.0; }
};

// Over the plan's microphone positions × the scene's sources (headings do not change the path).
DirectPathCount count_blocked_direct_paths(const Scene& scene, const SynthPlan& plan);

}  // namespace neraf::sim
