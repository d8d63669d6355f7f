#pragma once
// What a dataset folder contains: which of the published layouts (and the simulator's scene
// description) are present. A folder can hold several: a SoundSpaces or RAF scene also carries a
// nerfstudio transforms.json for its images.
#include <string>

namespace neraf::data {

struct DatasetLayout {
  bool soundspaces = false;  // binaural_rirs/ or metadata/points.txt
  bool raf = false;          // data/ (RIR folders) or metadata/data-split.json
  bool nerfstudio = false;   // transforms.json
  bool simulated = false;    // scene.json written by `neraf simulate`

  bool has_audio() const { return soundspaces || raf; }
  bool empty() const { return !soundspaces && !raf && !nerfstudio; }
  // "soundspaces + nerfstudio images (simulated)" etc.; "nothing recognised" when empty.
  std::string describe() const;
};

DatasetLayout detect_layout(const std::string& dir);

}  // namespace neraf::data
