#pragma once
// Tiny joint-training fixtures: the data tests' SoundSpaces scene (5 train + 2 test binaural
// RIRs) written to a temp folder, plus a tiny acoustic configuration on top of the tiny vision one.
#include <torch/torch.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "../data/fixtures.h"
#include "neraf/data/rir_set.h"
#include "neraf/infer/train_config.h"
#include "synthetic_scene.h"

namespace neraf::infer::fixtures {

// A fresh temp folder (removed by the caller's TempDir or left in /tmp).
inline std::string make_temp_dir(const std::string& tag) {
  const auto base = std::filesystem::temp_directory_path() /
                    ("neraf_audio_" + tag + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(base);
  std::filesystem::create_directories(base);
  return base.string();
}

// Writes the SoundSpaces fixture into dir/scene and loads it (features cached under dir/cache).
inline data::RirSet tiny_rir_set(const std::string& dir, bool move_a_point = false) {
  neraf::data::testing::SoundSpacesScene scene;
  if (move_a_point) scene.points[2][0] += 0.5;
  const std::string root = dir + "/scene";
  scene.write(root);
  data::RirLoadOptions o;
  o.cache_dir = dir + "/cache";
  o.progress = false;
  return data::load_rir_set(root, o);
}

inline TrainConfig tiny_joint_config() {
  TrainConfig c = tiny_train_config();
  c.modality = Modality::joint;
  c.audio.grid_resolution = 32;  // the cpu ResNet3D needs ≥ 32³ (BatchNorm on 2³ at layer3)
  c.audio.cells_per_update = 512;
  c.audio.batch_size = 64;
  c.audio.start_step = -1;  // audio from the first step
  c.audio.nacf_width = 64;
  c.audio.nacf_layers = 2;
  c.audio.schedule = {1e-3, 1e-4, 1000, 0, 1e-8, "sine", 1e-15};
  return c;
}

}  // namespace neraf::infer::fixtures
