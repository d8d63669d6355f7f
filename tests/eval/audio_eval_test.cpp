// Audio evaluation: baseline neighbour selection, the eval JSON/CSV/PNG outputs of a run folder,
// the uncalibrated row of a calibrated run, the paired differences against each baseline, and the
// check that an ablation trained like the run it is compared with.
#include "neraf/eval/audio_eval.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <fstream>

#include "../infer/audio_test_util.h"
#include "neraf/infer/audio_field.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/calibration.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"

namespace neraf::eval {
namespace {

namespace fs = std::filesystem;
using infer::AudioRun;
using infer::TrainConfig;
using infer::fixtures::make_image_set;
using infer::fixtures::make_temp_dir;
using infer::fixtures::tiny_joint_config;
using infer::fixtures::tiny_rir_set;

data::Rir hand_rir(double mx, double my, double mz, double sx, int heading) {
  data::Rir r;
  r.mic = {mx, my, mz};
  r.source = {sx, 1.0, 0.0};
  r.heading_deg = heading;
  return r;
}

TEST(AudioBaselines, NearestPicksSameHeadingAndSourceClosestMic) {
  data::RirSet set;
  set.rirs = {
      hand_rir(0.0, 1.0, 0.0, 5.0, 90),  // 0 query (test)
      hand_rir(0.1, 1.0, 0.0, 5.0, 0),   // 1 closest mic but other heading
      hand_rir(0.2, 1.0, 0.0, 4.0, 90),  // 2 close mic, other source
      hand_rir(1.0, 1.0, 0.0, 5.0, 90),  // 3 same heading + source, far
      hand_rir(0.0, 1.0, 0.6, 5.0, 90),  // 4 same heading + source, nearest of those (0.6)
      hand_rir(0.0, 1.7, 0.0, 5.0, 90),  // 5 same heading + source (0.7)
  };
  const std::vector<int64_t> train = {1, 2, 3, 4, 5};
  std::vector<double> d;
  const auto nb = nearest_training_rirs(set, train, set.rirs[0], 4, &d);
  ASSERT_EQ(nb.size(), 3u);  // only 3, 4, 5 qualify
  EXPECT_EQ(nb[0], 4);
  EXPECT_EQ(nb[1], 5);
  EXPECT_EQ(nb[2], 3);
  EXPECT_NEAR(d[0], 0.6, 1e-12);
  EXPECT_NEAR(d[2], 1.0, 1e-12);
  // Without any same-source candidate: same heading (mic + source distance) wins over others.
  const auto nb2 = nearest_training_rirs(set, {1, 2}, set.rirs[0], 1, &d);
  ASSERT_EQ(nb2.size(), 1u);
  EXPECT_EQ(nb2[0], 2);
  EXPECT_NEAR(d[0], 0.2 + 1.0, 1e-12);
  // No same heading at all: the closest pose overall.
  EXPECT_EQ(nearest_training_rirs(set, {1}, set.rirs[0], 1)[0], 1);
}

TEST(AudioEval, RunFolderPredictsAndWritesJsonCsvPng) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("eval");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  const TrainConfig c = tiny_joint_config();
  auto trainer = train::make_trainer(c, &images, torch::kCPU, &rirs);
  trainer->step();
  trainer->step();
  const std::string run = dir + "/run";
  trainer->save_checkpoint(infer::checkpoint_path(run, 2));
  io::write_json_atomically(run + "/config.json", infer::to_json(c));
  io::write_json_atomically(run + "/data.json", {{"audio", infer::make_audio_manifest(rirs)}});

  const AudioRun ar = infer::load_audio_run(run);
  EXPECT_EQ(ar.step(), 2);
  EXPECT_EQ(ar.info().channels, 2);
  EXPECT_EQ(ar.info().sample_rate, 22050);
  const torch::Tensor p = ar.predict_log_stft(rirs.rirs[5].mic, rirs.rirs[5].source, 90.0);
  EXPECT_EQ(p.sizes(), (std::vector<int64_t>{2, 257, rirs.max_len}));
  EXPECT_TRUE(torch::isfinite(p).all().item<bool>());
  const auto wave = ar.predict_waveform(rirs.rirs[5].mic, rirs.rirs[5].source, 90.0, 0, 1000);
  ASSERT_EQ(wave.size(), 2u);
  EXPECT_EQ(wave[0].size(), 1000u);

  AudioEvalOptions o;
  o.out_dir = dir + "/eval";
  o.num_images = 1;
  o.progress = false;
  const AudioEval e = evaluate_audio(ar, rirs, rirs.train, o);
  ASSERT_EQ(e.methods.size(), 4u);
  const nlohmann::json j = to_json(e);
  for (const char* m : {"neraf", "nearest", "linear", kGriffinLimFloorName})
    for (const char* k :
         {"t60_error_pct", "c50_error_db", "edt_error_s", "stft_error", "invalid_t60", "n_rirs"})
      EXPECT_TRUE(j.at(m).contains(k)) << m << "." << k;
  EXPECT_EQ(j["neraf"]["n_rirs"], 2);
  write_audio_csv(o.out_dir + "/audio_per_rir.csv", e);
  std::ifstream csv(o.out_dir + "/audio_per_rir.csv");
  int lines = 0;
  for (std::string l; std::getline(csv, l);) ++lines;
  EXPECT_EQ(lines, 1 + 4 * 2);
  EXPECT_TRUE(fs::exists(o.out_dir + "/audio_00000.png"));
  EXPECT_NE(audio_table(e.methods).find("nearest"), std::string::npos);

  // Any RIRs of a set in the same format (here: training RIRs, scored as if new): the same
  // prediction as the default split's path gives for them, baselines from the run's train set.
  const std::vector<int64_t> chosen = {rirs.train[0], rirs.train[1], rirs.train[2]};
  const AudioEval n = evaluate_audio(ar, rirs, {rirs.train[3]}, rirs, chosen, o);
  ASSERT_EQ(n.methods.size(), 4u);
  EXPECT_EQ(n.rir_ids.size(), 3u);
  EXPECT_EQ(n.rir_ids[1], rirs.rirs[static_cast<size_t>(chosen[1])].id);
  EXPECT_EQ(to_json(n)["linear"]["n_rirs"], 3);
  nlohmann::json manifest = infer::make_audio_manifest(rirs);
  EXPECT_NO_THROW(infer::check_same_room_format(manifest, rirs, "novel"));
  manifest["num_rirs"] = 1;  // another set of the same room: fine
  EXPECT_NO_THROW(infer::check_same_room_format(manifest, rirs, "novel"));
  manifest["sample_rate"] = 48000;
  try {
    infer::check_same_room_format(manifest, rirs, "novel");
    ADD_FAILURE() << "a different sample rate must be refused";
  } catch (const Error& err) {
    EXPECT_NE(std::string(err.what()).find("sample_rate"), std::string::npos) << err.what();
  }
}

// A calibrated run is scored twice: "neraf" with its calibration and "neraf_uncalibrated", which
// is exactly the run evaluated with its calibration removed (same RIRs, same Griffin-Lim seeds).
TEST(AudioEval, UncalibratedRowIsTheRunWithoutItsCalibration) {
  torch::manual_seed(0);
  const std::string dir = make_temp_dir("eval_uncal");
  const data::RirSet rirs = tiny_rir_set(dir);
  const data::ImageSet images = make_image_set();
  TrainConfig c = tiny_joint_config();
  ASSERT_TRUE(c.audio.energy_calibration);
  auto trainer = train::make_trainer(c, &images, torch::kCPU, &rirs);
  trainer->step();
  trainer->step();
  const std::string run = dir + "/run";
  trainer->save_checkpoint(infer::checkpoint_path(run, 2));
  io::write_json_atomically(run + "/config.json", infer::to_json(c));
  io::write_json_atomically(run + "/data.json", {{"audio", infer::make_audio_manifest(rirs)}});
  infer::calibrate_run(run, rirs);

  const AudioRun calibrated = infer::load_audio_run(run);
  ASSERT_TRUE(calibrated.calibration().defined());
  const AudioRun uncalibrated = infer::load_audio_run(run, torch::kCPU, "", nerf::Precision::fp32,
                                                      /*calibrated=*/false);
  ASSERT_FALSE(uncalibrated.calibration().defined());

  AudioEvalOptions o;
  o.progress = false;
  o.seed = 7;
  o.neraf_post_processing = kCalibratedGriffinLim;
  o.uncalibrated = &uncalibrated;
  const AudioEval e = evaluate_audio(calibrated, rirs, rirs.train, o);
  ASSERT_EQ(e.methods.size(), 5u);
  EXPECT_EQ(e.methods[0].name, "neraf");
  EXPECT_EQ(e.methods[0].post_processing, kCalibratedGriffinLim);
  EXPECT_EQ(e.methods[1].name, kUncalibratedName);
  EXPECT_EQ(e.methods[1].post_processing, kGriffinLim);
  EXPECT_EQ(e.methods[2].post_processing, kMeasuredWaveform);  // nearest
  EXPECT_EQ(e.methods[3].post_processing, kGriffinLim);        // linear
  EXPECT_EQ(e.methods[4].name, kGriffinLimFloorName);
  EXPECT_EQ(e.methods[4].post_processing, kGriffinLim);

  // The floor is each test RIR's own measured magnitudes through the same Griffin-Lim (the
  // seed of every row for that RIR), scored against its waveform: recomputed here.
  for (size_t n = 0; n < rirs.test.size(); ++n) {
    const int64_t i = rirs.test[n];
    const auto wave = infer::griffin_lim_channels(infer::log_stft_to_magnitude(rirs.features(i)),
                                                  rirs.stft, o.seed + n);
    io::AudioBuffer pred, gt;
    pred.sample_rate = gt.sample_rate = rirs.sample_rate;
    pred.channels = wave;
    const torch::Tensor w = rirs.waveform(i).to(torch::kFloat32).contiguous();
    for (int64_t c = 0; c < w.size(0); ++c)
      gt.channels.emplace_back(w[c].data_ptr<float>(), w[c].data_ptr<float>() + w.size(1));
    const metrics::RirErrors want =
        metrics::compare_rirs(pred, gt, metrics::Variant::soundspaces, "floor", "gt");
    EXPECT_EQ(e.methods[4].per_rir[n].stft_error, want.stft_error) << n;
    EXPECT_EQ(e.methods[4].per_rir[n].c50_error_db, want.c50_error_db) << n;
    EXPECT_EQ(e.methods[4].per_rir[n].t60_error_pct, want.t60_error_pct) << n;
  }

  // The reference: the run loaded without its calibration, scored as the only model.
  const AudioMethodEval alone = evaluate_audio_model(uncalibrated, rirs, rirs.test, "neraf", o);
  ASSERT_EQ(alone.per_rir.size(), e.methods[1].per_rir.size());
  bool calibration_changed_something = false;
  for (size_t n = 0; n < alone.per_rir.size(); ++n) {
    const auto &a = alone.per_rir[n], &u = e.methods[1].per_rir[n], &k = e.methods[0].per_rir[n];
    EXPECT_EQ(a.c50_error_db, u.c50_error_db) << n;
    EXPECT_EQ(a.stft_error, u.stft_error) << n;
    EXPECT_EQ(a.c50_pred_db, u.c50_pred_db) << n;
    if (a.stft_error != k.stft_error || a.c50_pred_db != k.c50_pred_db)
      calibration_changed_something = true;
  }
  EXPECT_TRUE(calibration_changed_something) << "the calibrated row equals the uncalibrated one";

  const nlohmann::json j = to_json(e);
  EXPECT_EQ(j["neraf"]["post_processing"], kCalibratedGriffinLim);
  EXPECT_EQ(j[kUncalibratedName]["post_processing"], kGriffinLim);
  EXPECT_EQ(j["nearest"]["post_processing"], kMeasuredWaveform);
  const nlohmann::json pu = paired_to_json(e, kUncalibratedName);
  ASSERT_TRUE(pu.contains("linear"));
  EXPECT_EQ(pu["linear"]["c50_error_db"]["n"], 2);
  EXPECT_NE(audio_table(e.methods).find(kCalibratedGriffinLim), std::string::npos);
  EXPECT_NE(paired_table(e, kUncalibratedName).find(kUncalibratedName), std::string::npos);
}

// An ablation may differ from the run it is compared with only in the ablation knobs.
TEST(AudioEval, TrainingDifferenceAllowsOnlyTheAblationKnobs) {
  const TrainConfig main = tiny_joint_config();
  const nlohmann::json main_data = {{"data", "runs/scene"},
                                    {"source", "runs/scene/transforms.json"},
                                    {"audio", {{"hash", "abc"}}}};
  const nlohmann::json mj = infer::to_json(main);
  EXPECT_EQ(training_difference(mj, main_data, mj, main_data), "");

  TrainConfig knobs = main;  // the ablated options and what does not change what is trained
  knobs.audio.grid = "zeros";
  knobs.audio.grid_resolution = 16;
  knobs.audio.relative_geometry = false;
  knobs.audio.position_max_freq_exp = 3;
  knobs.audio.average_fraction = 0.5;
  knobs.threads = 3;
  knobs.save_every = 7;
  knobs.audio.cache_dir = "/elsewhere";
  nlohmann::json moved = main_data;
  moved["data"] = "/abs/runs/scene";  // the same dataset named another way
  moved["source"] = "/abs/runs/scene/transforms.json";
  EXPECT_EQ(training_difference(mj, main_data, infer::to_json(knobs), moved), "");

  auto differs = [&](const TrainConfig& other, const std::string& key) {
    const std::string d = training_difference(mj, main_data, infer::to_json(other), main_data);
    EXPECT_NE(d.find(key), std::string::npos) << "expected " << key << " in '" << d << "'";
  };
  TrainConfig audio_only = main;
  audio_only.modality = infer::Modality::audio;
  differs(audio_only, "config.json modality: \"audio\" vs \"joint\"");
  TrainConfig longer = main;
  longer.steps = main.steps + 1;
  differs(longer, "config.json steps");
  TrainConfig schedule = main;
  schedule.audio.schedule.max_steps = 5;
  differs(schedule, "config.json audio.schedule.max_steps");
  TrainConfig seed = main;
  seed.seed = main.seed + 1;
  differs(seed, "config.json seed");
  TrainConfig preset = main;
  preset.preset = "paper";
  differs(preset, "config.json preset");
  TrainConfig frozen = main;
  frozen.audio.vision_run = "/some/other/run";
  differs(frozen, "audio.vision_run");

  nlohmann::json other_data = main_data;
  other_data["audio"]["hash"] = "def";
  EXPECT_NE(training_difference(mj, main_data, mj, other_data).find("data.json audio.hash"),
            std::string::npos);
}

// Paired neraf − baseline differences on hand-made per-RIR errors.
TEST(AudioEval, PairedDifferencesAgainstEachBaseline) {
  auto method = [](const std::string& name, std::vector<double> c50) {
    AudioMethodEval m{name, {}, {}};
    for (double v : c50) {
      metrics::RirErrors r;
      r.c50_error_db = v;
      r.t60_error_pct = 2.0;  // a tie on T60
      m.per_rir.push_back(r);
    }
    return m;
  };
  AudioEval e;
  e.rir_ids = {"a", "b", "c"};
  e.methods = {method("neraf", {0.5, 0.5, 1.0}), method("nearest", {1.0, 1.5, 1.5}),
               method("linear", {0.5, 1.0, 0.5})};
  const nlohmann::json j = paired_to_json(e);
  // nearest: differences −0.5, −1, −0.5 → mean −2/3, s.d. √(1/12), s.e. √(1/12)/√3 = 1/6.
  EXPECT_NEAR(j["nearest"]["c50_error_db"]["mean_difference"].get<double>(), -2.0 / 3.0, 1e-12);
  EXPECT_NEAR(j["nearest"]["c50_error_db"]["standard_error"].get<double>(), 1.0 / 6.0, 1e-12);
  EXPECT_EQ(j["nearest"]["c50_error_db"]["neraf_better"], 3);
  EXPECT_EQ(j["nearest"]["c50_error_db"]["n"], 3);
  // linear: 0, −0.5, +0.5 → mean 0, one RIR where neraf is better.
  EXPECT_NEAR(j["linear"]["c50_error_db"]["mean_difference"].get<double>(), 0.0, 1e-12);
  EXPECT_EQ(j["linear"]["c50_error_db"]["neraf_better"], 1);
  EXPECT_EQ(j["linear"]["t60_error_pct"]["neraf_better"], 0);
  EXPECT_TRUE(j["linear"]["edt_error_s"].contains("standard_error"));
  const std::string table = paired_table(e);
  EXPECT_NE(table.find("linear"), std::string::npos);
  EXPECT_NE(table.find("C50 -0.667"), std::string::npos) << table;
  // Without baselines (e.g. eval --no-baselines) there is nothing to pair.
  e.methods.resize(1);
  EXPECT_TRUE(paired_to_json(e).empty());
  EXPECT_EQ(paired_table(e), "");
}

}  // namespace
}  // namespace neraf::eval
