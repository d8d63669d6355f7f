// The acoustic branch in the trainer: checkpoint round trip and dataset/preset mismatch errors.
// (Few-shot subsets and loading: tests/infer/audio_run_test.cpp; baselines and the eval outputs:
// tests/eval/audio_eval_test.cpp.)
#include "neraf/train/audio_branch.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <memory>
#include <vector>

#include "../infer/audio_test_util.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"

namespace neraf::train {
namespace {

using infer::TrainConfig;
using infer::fixtures::make_image_set;
using infer::fixtures::make_temp_dir;
using infer::fixtures::tiny_joint_config;
using infer::fixtures::tiny_rir_set;

TEST(AudioBranch, JointStepReportsAudioLossesAndTouchesTheGrid) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("step");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  auto trainer = make_trainer(tiny_joint_config(), &images, torch::kCPU, &rirs);
  auto* audio = dynamic_cast<AudioBranch*>(trainer->branch("audio"));
  ASSERT_NE(audio, nullptr);
  EXPECT_EQ(audio->grid()->pointer(), 0);
  const StepResult r = trainer->step();
  EXPECT_TRUE(r.losses.count("audio_sc_loss"));
  EXPECT_TRUE(r.losses.count("audio_mag_loss"));
  EXPECT_TRUE(r.losses.count("rgb_loss"));
  EXPECT_GT(r.losses.at("audio_mag_loss"), 0.0);
  EXPECT_EQ(audio->grid()->pointer(), 512);
  // Written cells hold the field's values (alpha in [0,1], rgb in (0,1)); others stay zero.
  const torch::Tensor g = audio->grid()->grid().detach().reshape({7, -1});
  EXPECT_GT(
      g.index({torch::indexing::Slice(0, 3), torch::indexing::Slice(0, 512)}).min().item<double>(),
      0.0);
  EXPECT_EQ(
      g.index({torch::indexing::Slice(0, 4), torch::indexing::Slice(512, torch::indexing::None)})
          .abs()
          .max()
          .item<double>(),
      0.0);
  EXPECT_GT(trainer->group_lr("audio_fields"), 0.0);
}

TEST(SaturationWatch, FiresAfterPatienceStepsInARow) {
  SaturationWatch w;
  w.patience = 3;
  EXPECT_FALSE(w.saturated(0.95));
  EXPECT_FALSE(w.saturated(0.95));
  EXPECT_FALSE(w.saturated(0.5));  // the run is broken
  EXPECT_FALSE(w.saturated(1.0));
  EXPECT_FALSE(w.saturated(1.0));
  EXPECT_TRUE(w.saturated(0.91));
}

TEST(AudioBranch, SaturatedOutputsStopTrainingWithAMessage) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("saturated");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  auto trainer = make_trainer(tiny_joint_config(), &images, torch::kCPU, &rirs);
  auto* audio = dynamic_cast<AudioBranch*>(trainer->branch("audio"));
  {  // every output at −output_scale, where tanh has no gradient
    torch::NoGradGuard no_grad;
    for (auto& p : audio->model()->field()->named_parameters())
      if (p.key().rfind("STFT_linear", 0) == 0 && p.key().find("bias") != std::string::npos)
        p.value().fill_(-1000.0);
  }
  const StepResult first = trainer->step();
  EXPECT_NEAR(first.metrics.at("audio_saturated"), 1.0, 1e-12);
  int64_t steps = 1;
  try {
    for (; steps < 100; ++steps) trainer->step();
    FAIL() << "a saturated acoustic field trained on for 100 steps";
  } catch (const DivergedError& e) {
    EXPECT_NE(std::string(e.what()).find("saturated"), std::string::npos) << e.what();
  }
  EXPECT_EQ(steps, SaturationWatch{}.patience - 1);  // the step that made it `patience`
}

TEST(AudioBranch, BeforeStartStepOnlyTheGridMoves) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("start");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  TrainConfig c = tiny_joint_config();
  c.audio.start_step = 1;  // audio on steps 2, 3, ... (0-based index > 1)
  auto trainer = make_trainer(c, &images, torch::kCPU, &rirs);
  auto* audio = dynamic_cast<AudioBranch*>(trainer->branch("audio"));
  EXPECT_FALSE(trainer->step().losses.count("audio_mag_loss"));
  EXPECT_FALSE(trainer->step().losses.count("audio_mag_loss"));
  EXPECT_EQ(audio->grid()->pointer(), 1024);
  EXPECT_TRUE(trainer->step().losses.count("audio_mag_loss"));
}

TEST(AudioBranch, CheckpointRoundTripResumesExactly) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("ckpt");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  const TrainConfig c = tiny_joint_config();
  auto a = make_trainer(c, &images, torch::kCPU, &rirs);
  for (int i = 0; i < 3; ++i) a->step();
  const std::string path = dir + "/step3.pt";
  a->save_checkpoint(path);
  torch::manual_seed(123);  // different init: everything must come from the checkpoint
  auto b = make_trainer(c, &images, torch::kCPU, &rirs);
  b->load_checkpoint(path);
  auto* aa = dynamic_cast<AudioBranch*>(a->branch("audio"));
  auto* bb = dynamic_cast<AudioBranch*>(b->branch("audio"));
  EXPECT_EQ(bb->grid()->pointer(), aa->grid()->pointer());
  EXPECT_TRUE(torch::equal(bb->grid()->grid().detach(), aa->grid()->grid().detach()));
  const StepResult ra = a->step(), rb = b->step();
  EXPECT_EQ(rb.step, 4);
  EXPECT_DOUBLE_EQ(ra.losses.at("audio_mag_loss"), rb.losses.at("audio_mag_loss"));
  EXPECT_DOUBLE_EQ(ra.losses.at("audio_sc_loss"), rb.losses.at("audio_sc_loss"));
  EXPECT_DOUBLE_EQ(ra.losses.at("rgb_loss"), rb.losses.at("rgb_loss"));
}

TEST(AudioBranch, MismatchedDatasetOrPresetIsAClearError) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("mismatch");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::RirSet moved = tiny_rir_set(dir + "/other", /*move_a_point=*/true);
  const data::ImageSet images = make_image_set();
  const TrainConfig c = tiny_joint_config();
  auto a = make_trainer(c, &images, torch::kCPU, &rirs);
  a->step();
  const std::string path = dir + "/step1.pt";
  a->save_checkpoint(path);
  auto b = make_trainer(c, &images, torch::kCPU, &moved);
  try {
    b->load_checkpoint(path);
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("another RIR dataset"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("hash"), std::string::npos) << e.what();
  }
  // A manifest value of another type is a damaged run, not another dataset.
  nlohmann::json manifest = infer::make_audio_manifest(rirs);
  EXPECT_NO_THROW(infer::check_audio_manifest(manifest, rirs, dir));
  manifest["num_rirs"] = std::to_string(manifest["num_rirs"].get<int64_t>());
  try {
    infer::check_audio_manifest(manifest, rirs, dir);
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("the run's data.json is damaged (audio.num_rirs", 0), 0u)
        << e.what();
  }
  // Another preset (or grid mode) is refused by the header check.
  torch::serialize::InputArchive arch;
  infer::load_archive(arch, path);
  TrainConfig other = c;
  other.audio.grid = "none";
  EXPECT_THROW(infer::check_checkpoint_header(arch, other, path), Error);
  TrainConfig paper = c;
  paper.preset = "paper";
  EXPECT_THROW(infer::check_checkpoint_header(arch, paper, path), Error);
}

// A trainer over two scenes, each with its own frozen random field (seeds field_seed and
// field_seed + 1), its world map `maps[s]` and its own frames `frames` (empty: all).
std::unique_ptr<Trainer> two_scene_trainer(
    const TrainConfig& c, const data::RirSet& a, const data::RirSet& b, uint64_t field_seed,
    const std::vector<acoustic::WorldToField>& maps = {acoustic::kIdentityWorldToField,
                                                       acoustic::kIdentityWorldToField},
    const std::vector<int64_t>& frames = {}) {
  auto t = std::make_unique<Trainer>(c, torch::kCPU);
  std::vector<nerf::NerfactoModel> fields;
  for (uint64_t k = 0; k < 2; ++k) {
    fields.emplace_back(c.model, 4, field_seed + k);  // two different frozen fields
    for (auto& p : fields.back()->parameters()) p.set_requires_grad(false);
  }
  t->add_branch(std::make_unique<AudioBranch>(c, std::vector<const data::RirSet*>{&a, &b}, fields,
                                              maps, /*frozen_field=*/true, torch::kCPU, frames));
  return t;
}

// Multi-scene: two rooms (the second with one point moved, so its box and RIRs differ), each with
// its own frozen field and grid, one acoustic model; a batch mixes both; the checkpoint resumes
// exactly and is refused by a one-scene branch.
TEST(AudioBranch, MultiSceneStepsOverBothScenesAndResumesExactly) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("multi");
  const data::RirSet a = tiny_rir_set(dir + "/a");
  const data::RirSet b = tiny_rir_set(dir + "/b", /*move_a_point=*/true);
  TrainConfig c = tiny_joint_config();
  c.modality = infer::Modality::audio;
  auto make = [&](uint64_t field_seed) { return two_scene_trainer(c, a, b, field_seed); };
  auto t = make(7);
  auto* audio = dynamic_cast<AudioBranch*>(t->branch("audio"));
  ASSERT_EQ(audio->num_scenes(), 2u);
  // Each scene's grid is filled from its own field.
  EXPECT_FALSE(torch::equal(audio->grid(0)->grid(), audio->grid(1)->grid()));
  EXPECT_EQ(audio->train_rirs(1).size(), b.train.size());
  for (int i = 0; i < 2; ++i) {
    const StepResult r = t->step();
    EXPECT_GT(r.losses.at("audio_mag_loss"), 0.0);
    EXPECT_TRUE(std::isfinite(r.losses.at("audio_sc_loss")));
  }
  const std::string path = dir + "/multi.pt";
  t->save_checkpoint(path);
  torch::manual_seed(99);
  auto u = make(7);
  u->load_checkpoint(path);
  const StepResult ra = t->step(), rb = u->step();
  EXPECT_DOUBLE_EQ(ra.losses.at("audio_mag_loss"), rb.losses.at("audio_mag_loss"));
  EXPECT_DOUBLE_EQ(ra.losses.at("audio_sc_loss"), rb.losses.at("audio_sc_loss"));
  // A one-scene branch refuses the two-scene checkpoint, naming the count.
  auto one = std::make_unique<Trainer>(c, torch::kCPU);
  one->add_branch(std::make_unique<AudioBranch>(c, a, nerf::NerfactoModel(c.model, 4, 7),
                                                acoustic::kIdentityWorldToField,
                                                /*frozen_field=*/true, torch::kCPU));
  try {
    one->load_checkpoint(path);
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("trained on 2 scene(s)"), std::string::npos) << e.what();
  }
}

// Multi-scene with the scenes' own frames: the epoch permutation covers each scene's own slices
// only (a short scene's padding is never drawn); frames equal to max_len draw exactly what the
// branch without frame counts draws; a checkpoint drawn over other frames is refused.
TEST(AudioBranch, MultiSceneDrawsEachScenesOwnFrames) {
  const std::string dir = make_temp_dir("multiframes");
  const data::RirSet a = tiny_rir_set(dir + "/a");
  const data::RirSet b = tiny_rir_set(dir + "/b", /*move_a_point=*/true);
  TrainConfig c = tiny_joint_config();
  c.modality = infer::Modality::audio;
  const int64_t T = a.max_len;
  ASSERT_GT(T, 2);
  auto make = [&](const std::vector<int64_t>& frames) {
    torch::manual_seed(0);
    return two_scene_trainer(
        c, a, b, 7, {acoustic::kIdentityWorldToField, acoustic::kIdentityWorldToField}, frames);
  };
  auto saved_perm = [&](Trainer& t, const std::string& path) {
    t.save_checkpoint(path);
    torch::serialize::InputArchive archive, branch;
    infer::load_archive(archive, path);
    archive.read("branch_audio", branch);
    torch::Tensor perm;
    branch.read("perm", perm);
    return perm;
  };
  auto full = make({}), same = make({T, T}), own = make({T, 2});
  for (int i = 0; i < 2; ++i) {
    const StepResult x = full->step(), y = same->step(), z = own->step();
    EXPECT_DOUBLE_EQ(x.losses.at("audio_mag_loss"), y.losses.at("audio_mag_loss"));
    EXPECT_NE(x.losses.at("audio_mag_loss"), z.losses.at("audio_mag_loss"));  // other slices
  }
  const int64_t na = static_cast<int64_t>(a.train.size()),
                nb = static_cast<int64_t>(b.train.size());
  const torch::Tensor perm = saved_perm(*own, dir + "/own.pt");
  EXPECT_EQ(perm.numel(), na * T + nb * 2);
  EXPECT_EQ(saved_perm(*full, dir + "/full.pt").numel(), (na + nb) * T);
  try {
    make({T, 3})->load_checkpoint(dir + "/own.pt");
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("(RIR, frame) slices"), std::string::npos) << e.what();
  }
}

// Multi-scene with the grid read per query: each scene's positions reach its own grid through
// its own world map.
TEST(AudioBranch, MultiScenePerQueryFeaturesUseEachScenesWorldMap) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("multilocal");
  const data::RirSet a = tiny_rir_set(dir + "/a");
  const data::RirSet b = tiny_rir_set(dir + "/b", /*move_a_point=*/true);
  TrainConfig c = tiny_joint_config();
  c.modality = infer::Modality::audio;
  c.audio.grid_features = "local";
  const acoustic::WorldToField shifted = {0.5, 0, 0, 0.3, 0, 0.5, 0, 0, 0, 0, 0.5, -0.2};
  auto first_loss = [&](const acoustic::WorldToField& second_map) {
    torch::manual_seed(11);
    auto t = two_scene_trainer(c, a, b, 7, {acoustic::kIdentityWorldToField, second_map});
    const StepResult r = t->step();
    EXPECT_TRUE(std::isfinite(r.losses.at("audio_mag_loss")));
    return r.losses.at("audio_mag_loss");
  };
  const double same = first_loss(acoustic::kIdentityWorldToField);
  EXPECT_DOUBLE_EQ(same, first_loss(acoustic::kIdentityWorldToField));  // deterministic
  EXPECT_NE(same, first_loss(shifted));
}

}  // namespace
}  // namespace neraf::train
