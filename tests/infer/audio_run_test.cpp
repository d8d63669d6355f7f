// Loading a run's acoustic field: the few-shot subset, a vision run refused, and const queries
// from several threads at once giving the sequential results.
#include "neraf/infer/audio_run.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <vector>

#include "audio_test_util.h"
#include "neraf/infer/calibration.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/infer/exported_model.h"
#include "neraf/io/json_file.h"
#include "neraf/train/audio_branch.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"

namespace neraf::infer {
namespace {

using fixtures::make_image_set;
using fixtures::make_temp_dir;
using fixtures::tiny_joint_config;
using fixtures::tiny_rir_set;

TEST(AudioRun, FewShotSubsetIsSeededAndSized) {
  const std::string dir = make_temp_dir("subset");
  const data::RirSet rirs = tiny_rir_set(dir);
  ASSERT_EQ(rirs.train.size(), 5u);
  EXPECT_EQ(audio_train_subset(rirs, 1.0, 1), rirs.train);
  const auto s = audio_train_subset(rirs, 0.4, 7);
  EXPECT_EQ(s.size(), 2u);
  EXPECT_EQ(s, audio_train_subset(rirs, 0.4, 7));
  EXPECT_TRUE(std::is_sorted(s.begin(), s.end()));
  for (int64_t i : s)
    EXPECT_NE(std::find(rirs.train.begin(), rirs.train.end(), i), rirs.train.end());
  EXPECT_EQ(audio_train_subset(rirs, 0.01, 7).size(), 1u);
  EXPECT_THROW(audio_train_subset(rirs, 0.0, 7), Error);
}

TEST(AudioRun, VisionRunHasNoAcousticField) {
  const std::string dir = make_temp_dir("visiononly");
  TrainConfig c = fixtures::tiny_train_config();
  io::write_json_atomically(dir + "/config.json", to_json(c));
  EXPECT_THROW(load_audio_run(dir), Error);
}

// One AudioRun queried from two threads at once gives exactly the sequential predictions (the
// queries are const and switch no module mode), and the model stays in eval mode.
TEST(AudioRun, ConcurrentQueriesMatchSequentialOnes) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("threads");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  const TrainConfig c = tiny_joint_config();
  const std::string run_dir = dir + "/run";
  {
    auto trainer = train::make_trainer(c, &images, torch::kCPU, &rirs);
    trainer->step();
    trainer->save_checkpoint(checkpoint_path(run_dir, 1));
  }
  io::write_json_atomically(run_dir + "/config.json", to_json(c));
  io::write_json_atomically(run_dir + "/data.json", {{"audio", make_audio_manifest(rirs)}});
  EXPECT_FALSE(load_audio_run(run_dir).calibration().defined());  // saving does not calibrate
  calibrate_run(run_dir, rirs);                                   // the stage training ends with
  const AudioRun run = load_audio_run(run_dir);
  ASSERT_TRUE(run.calibration().defined());  // the cpu preset's energy calibration is applied
  EXPECT_FALSE(load_audio_run(run_dir, torch::kCPU, "", nerf::Precision::fp32, false)
                   .calibration()
                   .defined());
  // A calibration fitted for another step is refused, naming the file.
  save_calibration(checkpoint_path(run_dir, 1), 5, run.calibration());
  try {
    load_audio_run(run_dir);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("step-000000001.calibration.pt: fitted for another step"),
              std::string::npos)
        << e.what();
  }
  save_calibration(checkpoint_path(run_dir, 1), 1, run.calibration());
  EXPECT_FALSE(run.model()->is_training());

  const size_t n = rirs.rirs.size();
  auto query = [&](size_t i) {
    const data::Rir& r = rirs.rirs[i];
    return run.predict_log_stft(r.mic, r.source, r.heading_deg);
  };
  std::vector<torch::Tensor> expected;
  for (size_t i = 0; i < n; ++i) expected.push_back(query(i));
  const auto expected_wave =
      run.predict_waveform(rirs.rirs[0].mic, rirs.rirs[0].source, rirs.rirs[0].heading_deg, 3);

  constexpr int kRounds = 5;
  std::vector<torch::Tensor> got[2];
  std::vector<std::vector<float>> got_wave[2];
  std::string failure[2];
  auto worker = [&](int k) {
    try {
      for (int round = 0; round < kRounds; ++round)
        for (size_t j = 0; j < n; ++j) got[k].push_back(query(k == 0 ? j : n - 1 - j));
      got_wave[k] =
          run.predict_waveform(rirs.rirs[0].mic, rirs.rirs[0].source, rirs.rirs[0].heading_deg, 3);
    } catch (const std::exception& e) {
      failure[k] = e.what();
    }
  };
  std::thread a(worker, 0), b(worker, 1);
  a.join();
  b.join();
  for (int k = 0; k < 2; ++k) {
    ASSERT_EQ(failure[k], "") << "thread " << k;
    ASSERT_EQ(got[k].size(), kRounds * n);
    for (size_t q = 0; q < got[k].size(); ++q) {
      const size_t j = q % n, i = k == 0 ? j : n - 1 - j;
      EXPECT_TRUE(torch::equal(got[k][q], expected[i])) << "thread " << k << ", query " << q;
    }
    EXPECT_EQ(got_wave[k], expected_wave) << "thread " << k;
  }
  EXPECT_FALSE(run.model()->is_training());
}

// --audio-average: the saved "model_average" is the mean of the acoustic model's weights after
// each of the last share of audio steps (a slow reference: snapshots averaged in double), a run
// resumed inside the window ends with the same mean, and load_audio_run answers with it; "model"
// keeps the last step's weights for resuming.
TEST(AudioRun, WeightAveragedRunLoadsTheMeanOfItsLastSteps) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("average");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  TrainConfig c = tiny_joint_config();
  c.steps = 6;
  c.audio.average_fraction = 0.5;  // audio on steps 0..5 (start −1): the mean of steps 3, 4, 5
  const std::string run_dir = dir + "/run";
  auto trainer = train::make_trainer(c, &images, torch::kCPU, &rirs);
  auto* audio = dynamic_cast<train::AudioBranch*>(trainer->branch("audio"));
  ASSERT_NE(audio, nullptr);
  std::vector<torch::Tensor> sum;  // float64, per parameter
  for (int step = 0; step < 6; ++step) {
    trainer->step();
    if (step == 3) trainer->save_checkpoint(dir + "/step4.pt");  // one step into the window
    EXPECT_EQ(audio->averaged_steps(), std::max(0, step - 2)) << "after step " << step;
    if (step < 3) continue;
    const std::vector<torch::Tensor> w = audio->model()->parameters();
    for (size_t i = 0; i < w.size(); ++i) {
      const torch::Tensor x = w[i].detach().to(torch::kFloat64);
      if (sum.size() < w.size())
        sum.push_back(x.clone());
      else
        sum[i] += x;
    }
  }
  trainer->save_checkpoint(checkpoint_path(run_dir, 6));
  io::write_json_atomically(run_dir + "/config.json", to_json(c));
  io::write_json_atomically(run_dir + "/data.json", {{"audio", make_audio_manifest(rirs)}});
  const AudioRun run = load_audio_run(run_dir, torch::kCPU, "", nerf::Precision::fp32, false);
  const std::vector<torch::Tensor> loaded = run.model()->parameters();
  const std::vector<torch::Tensor> last = audio->model()->parameters();
  ASSERT_EQ(loaded.size(), sum.size());
  bool any_moved = false;
  for (size_t i = 0; i < sum.size(); ++i) {
    const torch::Tensor mean = sum[i] / 3.0;
    EXPECT_TRUE(torch::allclose(loaded[i].to(torch::kFloat64), mean, 1e-5, 1e-6)) << "param " << i;
    any_moved = any_moved || !torch::allclose(last[i].to(torch::kFloat64), mean, 1e-5, 1e-6);
  }
  EXPECT_TRUE(any_moved);  // the mean is not the last step's weights

  // Resumed one step into the window: the same two steps give the same mean, bit for bit.
  torch::manual_seed(123);
  auto resumed = train::make_trainer(c, &images, torch::kCPU, &rirs);
  resumed->load_checkpoint(dir + "/step4.pt");
  auto* audio_resumed = dynamic_cast<train::AudioBranch*>(resumed->branch("audio"));
  EXPECT_EQ(audio_resumed->averaged_steps(), 1);
  resumed->step();
  resumed->step();
  const std::string resumed_dir = dir + "/resumed";
  resumed->save_checkpoint(checkpoint_path(resumed_dir, 6));
  io::write_json_atomically(resumed_dir + "/config.json", to_json(c));
  io::write_json_atomically(resumed_dir + "/data.json", {{"audio", make_audio_manifest(rirs)}});
  const std::vector<torch::Tensor> again =
      load_audio_run(resumed_dir, torch::kCPU, "", nerf::Precision::fp32, false)
          .model()
          ->parameters();
  const std::vector<torch::Tensor> resumed_last = audio_resumed->model()->parameters();
  for (size_t i = 0; i < again.size(); ++i) {
    EXPECT_TRUE(torch::equal(again[i], loaded[i])) << "param " << i;
    EXPECT_TRUE(torch::equal(resumed_last[i], last[i])) << "param " << i;
  }
}

// A run that reads its grid per query (--grid-features both) answers through the world map of
// its data manifest, which it needs; the runtime export, which folds one feature per room into
// NAcF, refuses it.
TEST(AudioRun, PerQueryGridFeaturesReadTheManifestsWorldMap) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("local");
  const data::RirSet rirs = tiny_rir_set(dir);
  data::ImageSet images = make_image_set();
  images.world_scale = 0.5;
  TrainConfig c = tiny_joint_config();
  c.audio.grid_features = "both";
  const std::string run_dir = dir + "/run";
  {
    auto trainer = train::make_trainer(c, &images, torch::kCPU, &rirs);
    EXPECT_TRUE(std::isfinite(trainer->step().losses.at("audio_mag_loss")));
    trainer->save_checkpoint(checkpoint_path(run_dir, 1));
  }
  io::write_json_atomically(run_dir + "/config.json", to_json(c));
  nlohmann::json manifest = {{"audio", make_audio_manifest(rirs)},
                             {"world_transform", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}},
                             {"world_scale", 0.5}};
  io::write_json_atomically(run_dir + "/data.json", manifest);
  const data::Rir& r = rirs.rirs[0];
  const AudioRun run = load_audio_run(run_dir, torch::kCPU, "", nerf::Precision::fp32, false);
  EXPECT_EQ(run.model()->options().nacf.world_to_field, world_to_field(images));
  EXPECT_EQ(run.model()->options().nacf.world_to_field[0], 0.5);
  ASSERT_TRUE(run.scene_features().volume.defined());
  ASSERT_TRUE(run.scene_features().global.defined());
  const torch::Tensor a = run.predict_log_stft(r.mic, r.source, r.heading_deg);
  EXPECT_TRUE(torch::isfinite(a).all().item<bool>());
  // Another map reads the grid elsewhere: another prediction.
  manifest["world_transform"][0][3] = 0.7;
  io::write_json_atomically(run_dir + "/data.json", manifest);
  const torch::Tensor b = load_audio_run(run_dir, torch::kCPU, "", nerf::Precision::fp32, false)
                              .predict_log_stft(r.mic, r.source, r.heading_deg);
  EXPECT_FALSE(torch::allclose(a, b));
  try {
    export_model(run, dir + "/model.nrf");
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--grid-features both"), std::string::npos) << e.what();
  }
  manifest.erase("world_scale");
  io::write_json_atomically(run_dir + "/data.json", manifest);
  try {
    load_audio_run(run_dir);
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("data.json: its world_transform / world_scale"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace neraf::infer
