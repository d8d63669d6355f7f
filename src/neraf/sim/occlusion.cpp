#include "neraf/sim/occlusion.h"

#include "neraf/geometry/box.h"
#include "neraf/sim/scene_json.h"

namespace neraf::sim {

int first_blocking_box(const Scene& scene, const Vec3& a, const Vec3& b) {
  for (size_t i = 0; i < scene.furniture.size(); ++i) {
    const geometry::YawBox box = furniture_box(scene.furniture[i]);
    if (box.contains(a) || box.contains(b) || geometry::intersect(box, a, b - a, 0.0, 1.0, nullptr))
      return static_cast<int>(i);
  }
  return -1;
}

DirectPathCount count_blocked_direct_paths(const Scene& scene, const SynthPlan& plan) {
  DirectPathCount n;
  for (const Vec3& m : plan.microphones) {
    for (const Source& s : scene.sources) {
      ++n.pairs;
      n.blocked += first_blocking_box(scene, s.position, m) >= 0;
    }
  }
  return n;
}

}  // namespace neraf::sim
