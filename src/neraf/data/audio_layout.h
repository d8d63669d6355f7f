#pragma once
// The audio layouts a RirSet comes in and the box its positions are normalised by (rir_set.h),
// without LibTorch, for what reads them back from a run's manifest (infer/run_manifest.h).
#include "neraf/geometry/vec.h"

namespace neraf::data {

enum class AudioLayout {
  soundspaces,  // <scene>/binaural_rirs/{0,90,180,270}/<r>_<s>.wav + metadata/points.txt
  raf,          // <room>/data/<id>/{rir.wav, rx_pos.txt, tx_pos.txt} + metadata/data-split.json
};
const char* to_string(AudioLayout layout);  // "soundspaces" / "raf" (rir_set.cpp)

struct Aabb {
  geometry::Vec3 min, max;
};

}  // namespace neraf::data
