#include "neraf/data/layout.h"

#include <filesystem>

namespace fs = std::filesystem;

namespace neraf::data {

std::string DatasetLayout::describe() const {
  std::string s;
  auto add = [&](const std::string& part) { s += (s.empty() ? "" : " + ") + part; };
  if (soundspaces) add("SoundSpaces RIRs");
  if (raf) add("RAF RIRs");
  if (nerfstudio) add("nerfstudio images");
  if (s.empty()) s = "nothing recognised";
  if (simulated) s += " (simulated: scene.json)";
  return s;
}

DatasetLayout detect_layout(const std::string& dir) {
  DatasetLayout d;
  std::error_code ec;
  const fs::path root(dir);
  if (!fs::is_directory(root, ec)) return d;
  d.soundspaces = fs::is_directory(root / "binaural_rirs", ec) ||
                  fs::exists(root / "metadata" / "points.txt", ec);
  // RAF: the split file, or a data/ folder whose entries hold rir.wav.
  d.raf = fs::exists(root / "metadata" / "data-split.json", ec);
  if (!d.raf && fs::is_directory(root / "data", ec)) {
    int checked = 0;
    for (const auto& e : fs::directory_iterator(root / "data", ec)) {
      if (fs::exists(e.path() / "rir.wav", ec)) {
        d.raf = true;
        break;
      }
      if (++checked >= 16) break;
    }
  }
  d.nerfstudio = fs::exists(root / "transforms.json", ec);
  d.simulated = fs::exists(root / "scene.json", ec);
  return d;
}

}  // namespace neraf::data
