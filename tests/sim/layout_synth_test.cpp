// End-to-end `synthesize`: the files of both layouts exist with the exact names and formats, read
// back consistently, are byte-identical for a seed at any thread count, and never overwrite
// silently.
#include <gtest/gtest.h>
#include <omp.h>
#include <stb/stb_image.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include "neraf/io/atomic_file.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/sim/layout_writers.h"
#include "neraf/sim/microphones.h"
#include "neraf/sim/plan_drawing.h"
#include "neraf/sim/scene_json.h"
#include "neraf/sim/synthesize.h"
#include "neraf/util/error.h"

namespace neraf::sim {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path synth_temp_dir(const std::string& name) {
  auto d = fs::temp_directory_path() / ("neraf_synth_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

// A small but complete scene: 3 × 2.5 × 3 m, one box, 8 free grid points, short RIRs.
Scene small_scene() {
  Scene s;
  s.name = "small";
  s.size = {3, 2.5, 3};
  s.materials["wood"].albedo = {0.6, 0.4, 0.2};
  s.materials["wood"].texture.kind = "checker";
  s.furniture = {Box{{1.5, 0.4, 1.5}, {0.6, 0.8, 0.6}, 20, "wood"}};
  Source src;
  src.position = {0.7, 1.2, 2.3};
  s.sources = {src};
  s.microphones.grid.spacing_m = 1.0;
  s.microphones.grid.height_m = 0.5;  // low, so the box removes the centre point
  s.microphones.grid.wall_margin_m = 0.5;
  s.microphones.random.count = 6;
  s.cameras.train_count = 4;
  s.cameras.eval_count = 2;
  s.cameras.width = 24;
  s.cameras.height = 16;
  s.light.position = {1.5, 2.3, 1.5};
  s.acoustics.max_order = 3;
  s.acoustics.rir_length_s = 0.1;
  validate_scene(s, "small");
  return s;
}

SynthOptions options(const fs::path& out, uint64_t seed, const std::string& layout) {
  SynthOptions o;
  o.layout = layout;
  o.out_dir = out.string();
  o.seed = seed;
  o.progress = false;
  return o;
}

// Every regular file under `dir` (relative path → bytes).
std::map<std::string, std::string> tree(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file())
      out[fs::relative(e.path(), dir).string()] = io::read_text_file(e.path().string());
  }
  return out;
}

std::vector<std::string> split_line(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string f;
  while (std::getline(ss, f, sep)) out.push_back(f);
  return out;
}

void expect_png(const fs::path& path, int w, int h) {
  int iw = 0, ih = 0, ic = 0;
  ASSERT_TRUE(fs::exists(path)) << path;
  ASSERT_EQ(stbi_info(path.string().c_str(), &iw, &ih, &ic), 1) << path;
  EXPECT_EQ(iw, w);
  EXPECT_EQ(ih, h);
  EXPECT_EQ(ic, 3);
}

TEST(LayoutSynth, SoundSpacesFilesNamesAndFormats) {
  const Scene scene = small_scene();
  const fs::path out = synth_temp_dir("ss");
  const SynthSummary sum = synthesize(scene, options(out, 5, "soundspaces"));
  const auto mics = grid_microphone_positions(scene);
  ASSERT_EQ(mics.size(), 8u);  // 3 × 3 grid minus the point inside the box
  EXPECT_EQ(sum.num_rirs, 8 * 4 * 1);
  EXPECT_EQ(sum.num_train_rirs + sum.num_test_rirs, sum.num_rirs);
  EXPECT_EQ(sum.channels, 2);
  EXPECT_EQ(sum.sample_rate, 44100);

  // scene.json: the resolved scene.
  EXPECT_EQ(scene_to_json(load_scene((out / "scene.json").string())), scene_to_json(scene));
  // plan.png: the top-down plan (plan_drawing.h), the same picture draw_plan gives.
  {
    const PlanImage plan = draw_plan(scene, plan_synthesis(scene, "soundspaces", 5));
    expect_png(out / "plan.png", plan.width, plan.height);
  }

  // Images + transforms.json (eval_mode "filename" names).
  const json t = io::read_json((out / "transforms.json").string());
  EXPECT_EQ(t["camera_model"], "OPENCV");
  EXPECT_EQ(t["w"], 24);
  EXPECT_EQ(t["h"], 16);
  ASSERT_EQ(t["frames"].size(), 6u);
  const std::vector<std::string> want = {
      "images/train_frame_00000.png", "images/train_frame_00001.png",
      "images/train_frame_00002.png", "images/train_frame_00003.png",
      "images/eval_frame_00000.png",  "images/eval_frame_00001.png"};
  for (size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(t["frames"][i]["file_path"], want[i]);
    expect_png(out / want[i], 24, 16);
    const auto& m = t["frames"][i]["transform_matrix"];
    // The camera sits inside the room.
    EXPECT_TRUE(
        inside_room(scene, {m[0][3].get<double>(), m[1][3].get<double>(), m[2][3].get<double>()}));
  }

  // points.txt: mics then the source; NeRAF's [x, z, −y] gives our coordinates back.
  std::istringstream points(io::read_text_file((out / "metadata/points.txt").string()));
  std::vector<Vec3> world = mics;
  world.push_back(scene.sources[0].position);
  std::string line;
  size_t n = 0;
  while (std::getline(points, line)) {
    const auto f = split_line(line, '\t');
    ASSERT_EQ(f.size(), 4u);
    ASSERT_LT(n, world.size());
    EXPECT_EQ(f[0], std::to_string(n));
    EXPECT_NEAR(std::stod(f[1]), world[n].x, 1e-6);
    EXPECT_NEAR(std::stod(f[3]), world[n].y, 1e-6);
    EXPECT_NEAR(-std::stod(f[2]), world[n].z, 1e-6);
    ++n;
  }
  EXPECT_EQ(n, 9u);

  // split.json covers every RIR once; every entry's file exists with the right format.
  const json split = io::read_json((out / "metadata_AudioNeRF/split.json").string());
  std::set<std::string> entries;
  for (const char* part : {"train", "test"})
    for (const auto& e : split[part]) entries.insert(e.get<std::string>());
  EXPECT_EQ(entries.size(), 32u);
  EXPECT_EQ(split["test"].size(), 3u);  // round(0.1 · 32)
  for (int h : {0, 90, 180, 270}) {
    for (int r = 0; r < 8; ++r) {
      const std::string name =
          std::to_string(h) + "/" + std::to_string(r) + "_8";  // source = point 8
      EXPECT_EQ(entries.count(name), 1u) << name;
      EXPECT_TRUE(fs::exists(out / "binaural_rirs" / (name + ".wav"))) << name;
    }
  }
  const auto audio = io::read_audio((out / "binaural_rirs/90/3_8.wav").string());
  EXPECT_EQ(audio.sample_rate, 44100);
  ASSERT_EQ(audio.num_channels(), 2);
  EXPECT_EQ(audio.num_frames(), 4410);
  double peak = 0, energy_l = 0, energy_r = 0;
  for (size_t i = 0; i < 4410; ++i) {
    peak = std::max(
        {peak, double(std::abs(audio.channels[0][i])), double(std::abs(audio.channels[1][i]))});
    energy_l += audio.channels[0][i] * audio.channels[0][i];
    energy_r += audio.channels[1][i] * audio.channels[1][i];
  }
  EXPECT_GT(peak, 1e-3);  // not silent
  EXPECT_LE(peak, 0.5 + 1e-6);
  EXPECT_NE(energy_l, energy_r);  // binaural, not duplicated mono
  EXPECT_LE(sum.peak, 1.0);

  const json info = io::read_json((out / "synth_info.json").string());
  EXPECT_EQ(info["seed"], 5);
  EXPECT_EQ(info["num_rirs"], 32);
  EXPECT_EQ(info["layout"], "soundspaces");
  fs::remove_all(out);
}

TEST(LayoutSynth, RafFilesNamesAndFormats) {
  Scene scene = small_scene();
  scene.microphones.kind = "random";
  Source cardioid;
  cardioid.position = {2.4, 1.0, 0.6};
  cardioid.yaw_deg = 90;
  cardioid.directivity = "cardioid";
  scene.sources.push_back(cardioid);
  const fs::path out = synth_temp_dir("raf");
  const SynthSummary sum = synthesize(scene, options(out, 9, "raf"));
  ASSERT_EQ(sum.num_rirs, 12);  // 6 random microphones × 2 sources
  EXPECT_EQ(sum.channels, 1);
  const auto mics = random_microphone_positions(scene, 9);

  const json split = io::read_json((out / "metadata/data-split.json").string());
  ASSERT_EQ(split["train"].size(), 1u);
  ASSERT_EQ(split["test"].size(), 1u);
  EXPECT_TRUE(split.contains("validation"));
  EXPECT_EQ(split["train"][0].size() + split["test"][0].size(), 12u);
  EXPECT_EQ(split["test"][0].size(), 1u);

  for (int id = 0; id < 12; ++id) {
    const fs::path dir = out / "data" / raf_id(id);
    const int s = id / 6, r = id % 6;
    const auto audio = io::read_audio((dir / "rir.wav").string());
    EXPECT_EQ(audio.sample_rate, 48000);
    EXPECT_EQ(audio.num_channels(), 1);
    EXPECT_EQ(audio.num_frames(), 4800);
    const auto rx = split_line(io::read_text_file((dir / "rx_pos.txt").string()), ',');
    ASSERT_EQ(rx.size(), 3u);
    EXPECT_NEAR(std::stod(rx[0]), mics[r].x, 1e-6);
    EXPECT_NEAR(std::stod(rx[1]), mics[r].y, 1e-6);
    EXPECT_NEAR(std::stod(rx[2]), mics[r].z, 1e-6);
    const auto tx = split_line(io::read_text_file((dir / "tx_pos.txt").string()), ',');
    ASSERT_EQ(tx.size(), 7u);
    const double qx = std::stod(tx[0]), qy = std::stod(tx[1]), qz = std::stod(tx[2]),
                 qw = std::stod(tx[3]);
    // scipy as_euler('yxz')[0]: atan2(−R[2][0], R[2][2]) (see layout_format_test).
    const double yaw =
        std::atan2(-2 * (qx * qz - qw * qy), 1 - 2 * (qx * qx + qy * qy)) * 180 / M_PI;
    EXPECT_NEAR(yaw, scene.sources[s].yaw_deg, 1e-6);
    EXPECT_NEAR(std::stod(tx[4]), scene.sources[s].position.x, 1e-6);
    EXPECT_NEAR(std::stod(tx[6]), scene.sources[s].position.z, 1e-6);
  }

  const json t = io::read_json((out / "transforms.json").string());
  ASSERT_EQ(t["frames"].size(), 6u);
  EXPECT_FALSE(t.contains("orientation_override"));
  for (int i = 0; i < 6; ++i) {
    const std::string name = frame_file_name("", i);
    EXPECT_EQ(t["frames"][i]["file_path"], name);
    expect_png(out / name, 24, 16);
  }
  // nerfstudio's 90 % fraction rule on 6 frames: ceil(5.4) = 6 train, 0 eval.
  EXPECT_EQ(sum.num_train_images, 6);
  EXPECT_EQ(sum.num_eval_images, 0);
  EXPECT_FALSE(fs::exists(out / "binaural_rirs"));
  fs::remove_all(out);
}

TEST(LayoutSynth, SameSeedGivesByteIdenticalFilesAtAnyThreadCount) {
  const Scene scene = small_scene();
  const fs::path a = synth_temp_dir("det_a"), b = synth_temp_dir("det_b"),
                 c = synth_temp_dir("det_c");
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  synthesize(scene, options(a, 11, "soundspaces"));
  omp_set_num_threads(1);
  synthesize(scene, options(b, 11, "soundspaces"));
  omp_set_num_threads(saved);
  synthesize(scene, options(c, 12, "soundspaces"));
  const auto ta = tree(a), tb = tree(b), tc = tree(c);
  EXPECT_EQ(ta.size(),
            32u + 6u + 6u);  // RIRs, images, transforms/points/split/scene/synth_info/plan
  ASSERT_EQ(ta.size(), tb.size());
  for (const auto& [name, bytes] : ta) {
    ASSERT_TRUE(tb.count(name)) << name;
    EXPECT_TRUE(tb.at(name) == bytes) << name << " differs between runs with the same seed";
  }
  // Another seed moves the cameras and the split (and the late-reverb noise).
  EXPECT_NE(ta.at("transforms.json"), tc.at("transforms.json"));
  EXPECT_NE(ta.at("binaural_rirs/0/0_8.wav"), tc.at("binaural_rirs/0/0_8.wav"));
  for (const auto& d : {a, b, c}) fs::remove_all(d);
}

// A fixed gain (to share another set's scale) replaces the automatic one and scales every sample
// by exactly gain / automatic gain.
TEST(LayoutSynth, AGivenGainScalesTheWholeSet) {
  Scene scene = small_scene();
  scene.cameras.train_count = 1;
  scene.cameras.eval_count = 0;
  const fs::path a = synth_temp_dir("gain_auto"), b = synth_temp_dir("gain_fixed");
  const SynthSummary automatic = synthesize(scene, options(a, 2, "raf"));
  SynthOptions fixed = options(b, 2, "raf");
  fixed.gain = 3 * automatic.gain;
  const SynthSummary scaled = synthesize(scene, fixed);
  EXPECT_DOUBLE_EQ(scaled.gain, 3 * automatic.gain);
  EXPECT_NEAR(scaled.peak, 3 * automatic.peak, 1e-6);
  EXPECT_DOUBLE_EQ(io::read_json((b / "synth_info.json").string())["gain"].get<double>(),
                   scaled.gain);
  const auto x = io::read_audio((a / "data/000003/rir.wav").string());
  const auto y = io::read_audio((b / "data/000003/rir.wav").string());
  ASSERT_EQ(x.channels[0].size(), y.channels[0].size());
  for (size_t i = 0; i < x.channels[0].size(); ++i)
    ASSERT_NEAR(y.channels[0][i], 3 * x.channels[0][i], 1e-6) << i;
  for (const auto& d : {a, b}) fs::remove_all(d);
}

TEST(LayoutSynth, GainFromChecksTheRoomAndThePlausibleRange) {
  Scene scene = small_scene();
  scene.cameras.train_count = 1;
  scene.cameras.eval_count = 0;
  const fs::path a = synth_temp_dir("gain_from");
  const SynthSummary written = synthesize(scene, options(a, 2, "raf"));
  EXPECT_DOUBLE_EQ(synthesized_gain(a.string()).value(), written.gain);
  EXPECT_FALSE(room_difference(scene, a.string()).has_value());
  Scene bigger = scene;
  bigger.size.x += 1;
  EXPECT_EQ(room_difference(bigger, a.string()).value_or(""), "size");
  for (const json& bad : {json(1e30), json(0.0), json("0.5")}) {
    json info = io::read_json((a / "synth_info.json").string());
    info["gain"] = bad;
    io::write_json_atomically((a / "synth_info.json").string(), info);
    try {
      synthesized_gain(a.string());
      ADD_FAILURE() << "accepted gain " << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("synth_info.json: \"gain\" must be"), std::string::npos)
          << e.what();
    }
  }
  fs::remove_all(a);
}

TEST(LayoutSynth, ARoomWhereNoSoundArrivesInTimeIsRefusedBeforeWriting) {
  Scene scene = small_scene();
  scene.acoustics.speed_of_sound = 1;  // 0.1 m within the 0.1 s RIRs: no pair is that close
  const SynthPlan plan = plan_synthesis(scene, "raf", 2);
  try {
    check_sound_reaches_microphones(scene, plan, "scene \"small\"");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("scene \"small\": every RIR would be silent", 0), 0u)
        << e.what();
  }
  const fs::path out = synth_temp_dir("silent");
  fs::remove_all(out);
  EXPECT_THROW(synthesize(scene, options(out, 2, "raf")), Error);
  EXPECT_FALSE(fs::exists(out));
  scene.acoustics.speed_of_sound = 343;
  EXPECT_NO_THROW(check_sound_reaches_microphones(scene, plan, "scene"));
}

TEST(LayoutSynth, RefusesANonEmptyFolderUnlessForced) {
  Scene scene = small_scene();
  scene.cameras.train_count = 1;
  scene.cameras.eval_count = 0;
  const fs::path out = synth_temp_dir("force");
  fs::create_directories(out);
  io::write_text_atomically((out / "notes.txt").string(), "keep me");
  try {
    synthesize(scene, options(out, 1, "raf"));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(out.string() + ": the folder is not empty", 0), 0u)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(out / "data"));
  // --force replaces only a dataset synth wrote (not a run, real data or a home folder).
  SynthOptions forced = options(out, 1, "raf");
  forced.force = true;
  try {
    synthesize(scene, forced);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is not a dataset written by neraf synth"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  fs::remove(out / "notes.txt");
  EXPECT_NO_THROW(synthesize(scene, options(out, 1, "raf")));
  // --force replaces the folder as a whole, so one holding anything synth did not write (notes,
  // a run trained inside it) is refused, and kept.
  io::write_text_atomically((out / "notes.txt").string(), "keep me");
  try {
    synthesize(scene, forced);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("holds notes.txt"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  fs::remove(out / "notes.txt");
  EXPECT_NO_THROW(synthesize(scene, forced));
  EXPECT_TRUE(fs::exists(out / "data/000000/rir.wav"));
  // No temporary files or folders are left behind, beside it or in it.
  for (const auto& e : fs::recursive_directory_iterator(out))
    EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << e.path();
  for (const auto& e : fs::directory_iterator(out.parent_path()))
    EXPECT_EQ(e.path().filename().string().find("." + out.filename().string() + ".neraf.tmp-"),
              std::string::npos)
        << e.path();
  // A synthesis that fails half-way (a bad HRTF file, after the pictures) leaves the old dataset
  // as it was, and nothing in a new folder.
  const fs::path bad_hrtf = out.parent_path() / "not_a_sofa.sofa";
  io::write_text_atomically(bad_hrtf.string(), "not HDF5");
  Scene binaural = scene;
  SynthOptions failing = options(out, 1, "soundspaces");
  failing.force = true;
  failing.hrtf_path = bad_hrtf.string();
  EXPECT_THROW(synthesize(binaural, failing), Error);
  EXPECT_TRUE(fs::exists(out / "data/000000/rir.wav"));
  const fs::path fresh = synth_temp_dir("fails_fresh");
  failing.out_dir = fresh.string();
  EXPECT_THROW(synthesize(binaural, failing), Error);
  EXPECT_FALSE(fs::exists(fresh) && !fs::is_empty(fresh));
  fs::remove(bad_hrtf);
  EXPECT_THROW(synthesize(scene, options(synth_temp_dir("bad_layout"), 1, "nerf")), Error);
  fs::remove_all(out);
}

}  // namespace
}  // namespace neraf::sim
