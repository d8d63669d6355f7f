// What `synthesize` writes is what the dataset loaders (src/neraf/data) read back: positions,
// headings / source yaws, splits, images and their split rule.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>

#include "neraf/data/image_set.h"
#include "neraf/data/rir_set.h"
#include "neraf/sim/microphones.h"
#include "neraf/sim/scene_json.h"
#include "neraf/sim/synthesize.h"

namespace neraf::sim {
namespace {

namespace fs = std::filesystem;

Scene scene_for_loading() {
  Scene s;
  s.name = "loader";
  s.size = {3, 2.5, 3};
  s.furniture = {Box{{1.5, 0.4, 1.5}, {0.6, 0.8, 0.6}, 20, "wall"}};
  Source a, b;
  a.position = {0.7, 1.2, 2.3};
  b.position = {2.4, 1.0, 0.6};
  b.yaw_deg = 135;
  b.directivity = "cardioid";
  s.sources = {a, b};
  s.microphones.grid.spacing_m = 1.0;
  s.microphones.random.count = 5;
  s.cameras.train_count = 4;
  s.cameras.eval_count = 2;
  s.cameras.width = s.cameras.height = 16;
  s.light.position = {1.5, 2.3, 1.5};
  s.acoustics.max_order = 2;
  s.acoustics.rir_length_s = 0.1;
  validate_scene(s, "loader");
  return s;
}

fs::path synth(const Scene& s, const std::string& layout) {
  const fs::path out = fs::temp_directory_path() / ("neraf_loader_" + layout + "_" + std::to_string(::getpid()));
  fs::remove_all(out);
  SynthOptions o;
  o.layout = layout;
  o.out_dir = out.string();
  o.seed = 4;
  o.progress = false;
  synthesize(s, o);
  return out;
}

TEST(LayoutLoader, SoundSpacesLoadsWithOurPositionsAndHeadings) {
  const Scene s = scene_for_loading();
  const fs::path out = synth(s, "soundspaces");
  data::RirLoadOptions opt;
  opt.load_features = false;
  opt.progress = false;
  const data::RirSet set = data::load_rir_set(out.string(), opt);
  EXPECT_EQ(set.layout, data::AudioLayout::soundspaces);
  EXPECT_EQ(set.channels, 2);
  EXPECT_EQ(set.wav_sample_rate, 44100);
  const auto mics = grid_microphone_positions(s);
  ASSERT_EQ(set.size(), static_cast<int64_t>(mics.size() * 4 * 2));
  EXPECT_EQ(set.train.size() + set.test.size(), set.rirs.size());
  for (const auto& r : set.rirs) {
    // "<rot>/<r>_<s>": the loader's mic/source must be our world points (y up), heading = rot.
    const int rot = std::stoi(r.id.substr(0, r.id.find('/')));
    const auto us = r.id.find('_');
    const int ri = std::stoi(r.id.substr(r.id.find('/') + 1, us));
    const int si = std::stoi(r.id.substr(us + 1)) - static_cast<int>(mics.size());
    ASSERT_GE(si, 0);
    EXPECT_EQ(r.heading_deg, rot);
    EXPECT_NEAR(r.mic.x, mics[ri].x, 1e-6);
    EXPECT_NEAR(r.mic.y, mics[ri].y, 1e-6);
    EXPECT_NEAR(r.mic.z, mics[ri].z, 1e-6);
    EXPECT_NEAR(r.source.x, s.sources[si].position.x, 1e-6);
    EXPECT_NEAR(r.source.y, s.sources[si].position.y, 1e-6);
    EXPECT_NEAR(r.source.z, s.sources[si].position.z, 1e-6);
  }
  data::ImageLoadOptions io;
  io.progress = false;
  const data::ImageSet images = data::load_transforms_json(out.string(), io);
  EXPECT_EQ(images.train.size(), 4);
  EXPECT_EQ(images.eval.size(), 2);
  EXPECT_EQ(images.train.images.size(1), 16);
  fs::remove_all(out);
}

TEST(LayoutLoader, RafLoadsWithOurPositionsAndSourceYaws) {
  Scene s = scene_for_loading();
  s.microphones.kind = "random";
  const fs::path out = synth(s, "raf");
  data::RirLoadOptions opt;
  opt.load_features = false;
  opt.progress = false;
  const data::RirSet set = data::load_rir_set(out.string(), opt);
  EXPECT_EQ(set.layout, data::AudioLayout::raf);
  EXPECT_EQ(set.channels, 1);
  EXPECT_EQ(set.wav_sample_rate, 48000);
  const auto mics = random_microphone_positions(s, 4);
  ASSERT_EQ(set.size(), 10);
  for (const auto& r : set.rirs) {
    const int id = std::stoi(r.id);
    const int si = id / 5, ri = id % 5;
    EXPECT_NEAR(r.mic.x, mics[ri].x, 1e-6);
    EXPECT_NEAR(r.mic.z, mics[ri].z, 1e-6);
    EXPECT_NEAR(r.source.y, s.sources[si].position.y, 1e-6);
    EXPECT_NEAR(r.raw_yaw_deg, s.sources[si].yaw_deg, 1e-6);
    EXPECT_EQ(r.heading_deg, static_cast<int>(s.sources[si].yaw_deg));
  }
  data::ImageLoadOptions io;
  io.progress = false;
  const data::ImageSet images = data::load_transforms_json(out.string(), io);
  // 6 frames, nerfstudio fraction rule: ceil(5.4) = 6 train, none left for eval.
  EXPECT_EQ(images.train.size() + images.eval.size(), 6);
  fs::remove_all(out);
}

}  // namespace
}  // namespace neraf::sim
