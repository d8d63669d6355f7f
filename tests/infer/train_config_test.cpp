// The training config: JSON round trip of the presets, and resolve_train_config's rules (what
// `neraf train` resolves from its flags).
#include "neraf/infer/train_config.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "neraf/acoustic/acoustic_model.h"
#include "neraf/data/rir_set.h"
#include "neraf/infer/audio_run.h"
#include "neraf/util/error.h"
#include "neraf/util/number_text.h"

namespace neraf::infer {
namespace {

TrainConfig resolve(const std::string& preset, Modality modality, TrainFlags flags = {}) {
  flags.preset = preset;
  flags.modality = modality;
  return resolve_train_config(flags);
}

TEST(TrainConfig, JsonRoundTrip) {
  for (const char* name : {"cpu", "paper", "reference"}) {
    TrainConfig c = train_preset(name);
    c.seed = 1234;
    const auto j = to_json(c);
    const TrainConfig back = train_config_from_json(j, "test");
    EXPECT_EQ(to_json(back), j);
    EXPECT_EQ(j["model"]["field"]["grid"]["log2_hashmap_size"],
              std::string(name) == "cpu" ? 17 : 19);
  }
  EXPECT_THROW(train_config_from_json(nlohmann::json::parse(R"({"preset": "gpu"})"), "x"),
               neraf::Error);
  EXPECT_THROW(train_config_from_json(nlohmann::json::parse(R"({"stepz": 3})"), "x"), neraf::Error);
}

TEST(ResolveTrainConfig, DefaultFlagsAreTheCpuJointRun) {
  const TrainConfig c = resolve_train_config(TrainFlags{});
  EXPECT_EQ(c.preset, "cpu");
  EXPECT_EQ(c.modality, Modality::joint);
  EXPECT_EQ(to_json(c).dump(), [] {
    TrainConfig p = train_preset("cpu");
    p.modality = Modality::joint;
    p.steps_from_data = true;  // no --steps: the run's data decides (FitRunLengthToData)
    return to_json(p).dump();
  }());
}

TEST(ResolveTrainConfig, CpuRunLengthPerModality) {
  const TrainConfig joint = resolve("cpu", Modality::joint);
  EXPECT_EQ(joint.steps, 3000);
  EXPECT_EQ(joint.fields.max_steps, 3000);
  EXPECT_EQ(joint.proposal_networks.max_steps, 3000);
  EXPECT_EQ(joint.audio.schedule.max_steps, 3000);
  EXPECT_EQ(joint.audio.start_step, 1000);
  // The acoustic field warms up when it starts (at full LR from its first step it could
  // saturate and stop learning).
  EXPECT_EQ(joint.audio.schedule.warmup_start, 1000);
  EXPECT_EQ(joint.audio.schedule.warmup_steps, 100);

  // Vision alone: 2000 steps, the tied schedules follow; camera_opt has its own decay.
  const TrainConfig vision = resolve("cpu", Modality::vision);
  EXPECT_EQ(vision.steps, 2000);
  EXPECT_EQ(vision.fields.max_steps, 2000);
  EXPECT_EQ(vision.proposal_networks.max_steps, 2000);
  EXPECT_EQ(vision.camera_opt.max_steps, train_preset("cpu").camera_opt.max_steps);

  // Audio on a frozen field: 1500 steps, audio from the first step after a 100-step warm-up.
  const TrainConfig audio = resolve("cpu", Modality::audio);
  EXPECT_EQ(audio.steps, 1500);
  EXPECT_EQ(audio.audio.schedule.max_steps, 1500);
  EXPECT_EQ(audio.audio.start_step, -1);
  EXPECT_EQ(audio.audio.schedule.warmup_start, 0);
  EXPECT_EQ(audio.audio.schedule.warmup_steps, 100);
}

TEST(ResolveTrainConfig, FitRunLengthToData) {
  // A small room keeps the fixed schedule: 2000 audio steps joint, 1500 audio-only.
  TrainConfig joint = resolve("cpu", Modality::joint);
  ASSERT_TRUE(joint.steps_from_data);
  RunLengthFit fit = fit_run_length_to_data(joint, 371 * 86);
  EXPECT_EQ(fit.audio_steps_before, 1999);  // steps 1001..2999
  EXPECT_EQ(fit.audio_steps_after, 1999);
  EXPECT_EQ(joint.steps, 3000);

  // 8 passes over 200k slices of 512: 3125 audio steps; the tied decays follow the new length,
  // the audio start and warm-up do not move.
  fit = fit_run_length_to_data(joint, 200000);
  EXPECT_EQ(fit.audio_steps_after, 3125);
  EXPECT_EQ(joint.steps, 1001 + 3125);
  EXPECT_EQ(joint.fields.max_steps, joint.steps);
  EXPECT_EQ(joint.audio.schedule.max_steps, joint.steps);
  EXPECT_EQ(joint.audio.start_step, 1000);
  EXPECT_EQ(joint.audio.schedule.warmup_start, 1000);
  EXPECT_EQ(joint.audio.schedule.warmup_steps, 100);

  // The 20k-RIR apartment (18,413 train RIRs × 86 frames) gets the cap, audio-only as joint.
  TrainConfig audio = resolve("cpu", Modality::audio);
  fit = fit_run_length_to_data(audio, 18413 * 86);
  EXPECT_EQ(fit.audio_steps_before, 1500);
  EXPECT_EQ(fit.audio_steps_after, kCpuMaxAudioSteps);
  EXPECT_EQ(audio.steps, kCpuMaxAudioSteps);
  EXPECT_EQ(audio.audio.schedule.max_steps, kCpuMaxAudioSteps);

  // --steps, the paper preset and vision runs keep their length.
  TrainFlags f;
  f.steps = 5000;
  TrainConfig given = resolve("cpu", Modality::joint, f);
  EXPECT_FALSE(given.steps_from_data);
  EXPECT_EQ(fit_run_length_to_data(given, 18413 * 86).audio_steps_after, 3999);
  EXPECT_EQ(given.steps, 5000);
  TrainConfig paper = resolve("paper", Modality::joint);
  EXPECT_FALSE(paper.steps_from_data);
  fit_run_length_to_data(paper, 18413 * 86);
  EXPECT_EQ(paper.steps, 400001);
  EXPECT_FALSE(resolve("cpu", Modality::vision).steps_from_data);

  // Recorded in config.json; a config without the key (an older run) reads as not fitted.
  EXPECT_TRUE(train_config_from_json(to_json(joint), "x").steps_from_data);
  nlohmann::json old = to_json(joint);
  old.erase("steps_from_data");
  EXPECT_FALSE(train_config_from_json(old, "x").steps_from_data);
}

TEST(ResolveTrainConfig, PaperRunLengthPerModality) {
  const TrainConfig paper = train_preset("paper");
  const TrainConfig joint = resolve("paper", Modality::joint);
  EXPECT_EQ(joint.steps, 400001);                             // NeRAF's max_num_iterations
  EXPECT_EQ(joint.fields.max_steps, paper.fields.max_steps);  // nerfstudio's own decay
  EXPECT_EQ(joint.audio.start_step, 2000);
  EXPECT_EQ(joint.audio.schedule.max_steps, paper.audio.schedule.max_steps);

  EXPECT_EQ(resolve("paper", Modality::vision).steps, 30000);

  const TrainConfig audio = resolve("paper", Modality::audio);
  EXPECT_EQ(audio.steps, 398000);
  EXPECT_EQ(audio.audio.start_step, -1);
  EXPECT_EQ(audio.audio.schedule.warmup_steps, 2000);
  EXPECT_EQ(audio.audio.schedule.max_steps, paper.audio.schedule.max_steps);
  EXPECT_EQ(audio.rays_per_batch, 4096);
}

TEST(ResolveTrainConfig, AudioWarmupIsCappedAtHalfAShortRun) {
  TrainFlags f;
  f.steps = 100;
  TrainConfig c = resolve("cpu", Modality::audio, f);
  EXPECT_EQ(c.steps, 100);
  EXPECT_EQ(c.audio.schedule.max_steps, 100);
  EXPECT_EQ(c.audio.schedule.warmup_steps, 50);
  f.steps = 1;
  c = resolve("cpu", Modality::audio, f);
  EXPECT_EQ(c.audio.schedule.warmup_steps, 0);
  // A long run keeps the full warm-up.
  f.steps = 5000;
  EXPECT_EQ(resolve("cpu", Modality::audio, f).audio.schedule.warmup_steps, 100);
  // Joint runs: capped at half of what follows the audio start (step 1000).
  f.steps = 1500;
  EXPECT_EQ(resolve("cpu", Modality::joint, f).audio.schedule.warmup_steps, 100);
  f.steps = 1100;
  EXPECT_EQ(resolve("cpu", Modality::joint, f).audio.schedule.warmup_steps, 50);
}

TEST(ResolveTrainConfig, ExplicitFlagsWin) {
  TrainFlags f;
  f.steps = 500;
  f.seed = 7;
  f.threads = 3;
  f.rays = 128;
  f.precision = nerf::Precision::fp32;
  f.grid = "zeros";
  f.audio_fraction = 0.5;
  f.decay_loss = 0.25;
  f.audio_loss = "sc_sll1";
  f.grid_resolution = 16;
  f.grid_features = "both";
  f.position_max_freq_exp = 3;
  f.decay_heads = true;
  f.audio_average = 0.25;
  f.no_relative_geometry = true;
  for (Modality m : {Modality::vision, Modality::joint}) {
    const TrainConfig c = resolve("cpu", m, f);
    EXPECT_EQ(c.steps, 500);  // over the modality's default
    EXPECT_EQ(c.fields.max_steps, 500);
    EXPECT_EQ(c.audio.schedule.max_steps, 500);
    EXPECT_EQ(c.seed, 7u);
    EXPECT_EQ(c.threads, 3);
    EXPECT_EQ(c.rays_per_batch, 128);
    EXPECT_EQ(c.model.precision, nerf::Precision::fp32);
    EXPECT_EQ(c.audio.grid, "zeros");
    EXPECT_EQ(c.audio.fraction, 0.5);
    EXPECT_EQ(c.audio.decay_weight, 0.25);
    EXPECT_EQ(c.audio.loss, "sc_sll1");
    EXPECT_EQ(c.audio.grid_resolution, 16);
    EXPECT_EQ(c.audio.grid_features, "both");
    EXPECT_EQ(c.audio.position_max_freq_exp, 3);
    EXPECT_TRUE(c.audio.decay_heads);
    EXPECT_EQ(c.audio.average_fraction, 0.25);
    EXPECT_FALSE(c.audio.relative_geometry);
  }
  // Unset flags keep the preset's values.
  const TrainConfig cpu = resolve("cpu", Modality::joint);
  const TrainConfig preset = train_preset("cpu");
  EXPECT_EQ(cpu.threads, preset.threads);
  EXPECT_EQ(cpu.rays_per_batch, 2048);
  EXPECT_EQ(cpu.model.precision, preset.model.precision);
  EXPECT_EQ(cpu.audio.decay_weight, preset.audio.decay_weight);
  EXPECT_TRUE(cpu.audio.relative_geometry);
  EXPECT_EQ(cpu.audio.loss, "sc_slmse");
  EXPECT_EQ(cpu.audio.grid_resolution, 32);
  EXPECT_EQ(cpu.audio.grid_features, "global");  // the published design
  EXPECT_FALSE(cpu.audio.decay_heads);
  EXPECT_EQ(cpu.audio.average_fraction, 0.0);  // the last step's weights
  EXPECT_EQ(resolve("paper", Modality::joint).audio.grid_resolution, 128);
  EXPECT_EQ(resolve("paper", Modality::joint).seed, 42u);
}

TEST(ResolveTrainConfig, AudioStartStepMovesTheWarmup) {
  TrainFlags f;
  f.audio_start_step = 500;
  TrainConfig c = resolve("cpu", Modality::joint, f);
  EXPECT_EQ(c.audio.start_step, 500);
  EXPECT_EQ(c.audio.schedule.warmup_start, 500);  // the cpu warm-up begins at the audio start
  EXPECT_EQ(c.audio.schedule.warmup_steps, 100);
  f.audio_start_step = -1;
  c = resolve("cpu", Modality::joint, f);
  EXPECT_EQ(c.audio.start_step, -1);
  EXPECT_EQ(c.audio.schedule.warmup_start, 0);
  EXPECT_EQ(c.audio.schedule.warmup_steps, 100);
  f.audio_start_step = 200;
  c = resolve("cpu", Modality::audio, f);
  EXPECT_EQ(c.audio.start_step, 200);
  EXPECT_EQ(c.audio.schedule.warmup_start, 200);
  EXPECT_EQ(c.audio.schedule.warmup_steps, 100);
  // The paper preset's warm-up (the reference's) runs from step 0 up to the audio start.
  f.audio_start_step = 500;
  c = resolve("paper", Modality::joint, f);
  EXPECT_EQ(c.audio.schedule.warmup_start, 0);
  EXPECT_EQ(c.audio.schedule.warmup_steps, 500);
}

TEST(ResolveTrainConfig, VisionRunOnlyWithAudioAndAbsolute) {
  TrainFlags f;
  f.vision_runs = {"runs/../runs/vision"};
  for (Modality m : {Modality::vision, Modality::joint}) {
    try {
      resolve("cpu", m, f);
      ADD_FAILURE() << "--vision-run must be refused without --modality audio";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--vision-run"), std::string::npos) << e.what();
    }
  }
  const TrainConfig c = resolve("cpu", Modality::audio, f);
  EXPECT_EQ(c.audio.vision_run,
            (std::filesystem::current_path() / "runs" / "vision").lexically_normal().string());
  EXPECT_TRUE(resolve("cpu", Modality::audio).audio.vision_run.empty());
  EXPECT_TRUE(c.audio.vision_runs.empty());  // one scene: the single-scene config, unchanged
  EXPECT_EQ(num_scenes(c), 1);
  // Two --vision-run: a multi-scene run, every run absolute, the first also audio.vision_run.
  f.vision_runs.push_back("runs/b");
  const TrainConfig multi = resolve("cpu", Modality::audio, f);
  ASSERT_EQ(multi.audio.vision_runs.size(), 2u);
  EXPECT_EQ(multi.audio.vision_runs[0], c.audio.vision_run);
  EXPECT_EQ(multi.audio.vision_run, c.audio.vision_run);
  EXPECT_EQ(multi.audio.vision_runs[1],
            (std::filesystem::current_path() / "runs" / "b").lexically_normal().string());
  EXPECT_EQ(num_scenes(multi), 2);
  validate(multi, "config");
  TrainConfig joint = multi;
  joint.modality = Modality::joint;
  EXPECT_THROW(validate(joint, "config"), Error);  // joint multi-scene is refused
}

// `reference` is the published model exactly: paper's sizes and schedule, no calibration, no
// relative geometry, the reference position encoding, its 18 viewing directions and its BatchNorm;
// the options are in config.json and reach the model a run builds.
TEST(TrainConfig, ReferencePresetIsThePublishedModel) {
  const TrainConfig paper = train_preset("paper");
  const TrainConfig ref = train_preset("reference");
  EXPECT_EQ(ref.preset, "reference");
  EXPECT_FALSE(ref.audio.energy_calibration);
  EXPECT_FALSE(ref.audio.relative_geometry);
  EXPECT_EQ(ref.audio.position_max_freq_exp, 8.0);
  EXPECT_EQ(ref.audio.view_directions, "reference");
  EXPECT_EQ(ref.audio.resnet_batch_norm, "running");
  EXPECT_EQ(ref.audio.early_fraction, 0.0);
  EXPECT_EQ(ref.audio.decay_weight, 0.0);
  // paper and cpu keep ours.
  for (const TrainConfig& x : {paper, train_preset("cpu")}) {
    EXPECT_EQ(x.audio.view_directions, "spread");
    EXPECT_EQ(x.audio.resnet_batch_norm, "grid");
  }
  // Apart from those two, reference is paper, flag for flag (the radiance field included).
  nlohmann::json a = to_json(ref), b = to_json(paper);
  for (nlohmann::json* j : {&a, &b}) {
    j->erase("preset");
    (*j)["audio"].erase("view_directions");
    (*j)["audio"].erase("resnet_batch_norm");
  }
  EXPECT_EQ(a, b);
  const TrainConfig joint = resolve("reference", Modality::joint);
  EXPECT_EQ(joint.steps, 400001);
  EXPECT_EQ(joint.audio.start_step, 2000);
  EXPECT_EQ(joint.audio.schedule.max_steps, 1002000);
  EXPECT_EQ(resolve("reference", Modality::audio).steps, 398000);
  // Recorded in config.json, read back as written.
  nlohmann::json j = to_json(joint);
  EXPECT_EQ(j["audio"]["view_directions"], "reference");
  EXPECT_EQ(j["audio"]["resnet_batch_norm"], "running");
  EXPECT_EQ(to_json(train_config_from_json(j, "config.json")), j);
  // A config.json older than the options (no keys) takes its preset's: ours for cpu and paper.
  nlohmann::json old = to_json(resolve("paper", Modality::joint));
  old["audio"].erase("view_directions");
  old["audio"].erase("resnet_batch_norm");
  EXPECT_EQ(train_config_from_json(old, "config.json").audio.view_directions, "spread");
  // The model a run builds honours them.
  data::Aabb box{{-1, 0, -1}, {3, 2, 3}};
  const acoustic::AcousticModelOptions o = audio_model_options(joint, 1, 513, 60, box);
  EXPECT_EQ(o.grid.view_directions, acoustic::ViewDirections::kReference);
  EXPECT_TRUE(o.resnet.running_stats);
  EXPECT_FALSE(o.nacf.relative_geometry);
  EXPECT_EQ(o.nacf.position_max_freq_exp, 8.0);
  EXPECT_EQ(o.nacf.in_features(), 1187);
  EXPECT_EQ(o.nacf.trunk, (std::vector<int64_t>{5096, 2048, 1024, 1024, 512}));
  EXPECT_EQ(o.grid.resolution, 128);
  const acoustic::AcousticModelOptions p =
      audio_model_options(resolve("paper", Modality::joint), 1, 513, 60, box);
  EXPECT_EQ(p.grid.view_directions, acoustic::ViewDirections::kSpread);
  EXPECT_FALSE(p.resnet.running_stats);
  // A hand-edited value is refused, naming the key.
  TrainConfig bad = joint;
  bad.audio.resnet_batch_norm = "batch";
  EXPECT_THROW(validate(bad, "config.json"), Error);
  bad = joint;
  bad.audio.view_directions = "fibonacci";
  EXPECT_THROW(validate(bad, "config.json"), Error);
  bad = joint;
  bad.audio.average_fraction = 1.5;
  EXPECT_THROW(validate(bad, "config.json"), Error);
  EXPECT_NO_THROW(validate(joint, "config.json"));
}

// Steps are numbered 0..steps−1 and audio runs after start_step: start = steps − 1 trains no
// acoustic field at all (it used to pass, and be calibrated and exported untrained).
TEST(TrainConfig, AtLeastOneAudioStep) {
  TrainConfig c = train_preset("cpu");
  c.modality = Modality::joint;
  c.steps = 2;
  c.audio.start_step = 1;
  EXPECT_THROW(validate(c, "config.json"), Error);
  c.audio.start_step = 0;
  EXPECT_NO_THROW(validate(c, "config.json"));
}

TEST(TrainConfig, GridResolutionMustPassTheSceneEncoder) {
  TrainConfig c = train_preset("cpu");
  c.modality = Modality::joint;
  c.audio.grid_resolution = 16;  // halved four times: one voxel at the last BatchNorm
  EXPECT_THROW(validate(c, "config.json"), Error);
  c.audio.grid_resolution = 17;
  EXPECT_NO_THROW(validate(c, "config.json"));
  c.audio.grid_resolution = 16;
  c.audio.grid = "none";  // no encoder
  EXPECT_NO_THROW(validate(c, "config.json"));
}

TEST(TrainConfig, PerQueryGridFeaturesNeedAGridAndRoundTrip) {
  TrainConfig c = train_preset("cpu");
  c.modality = Modality::joint;
  c.audio.grid_features = "local";
  EXPECT_NO_THROW(validate(c, "config.json"));
  EXPECT_EQ(train_config_from_json(to_json(c), "config.json").audio.grid_features, "local");
  c.audio.grid = "none";
  EXPECT_THROW(validate(c, "config.json"), Error);
  c.audio.grid = "zeros";
  EXPECT_NO_THROW(validate(c, "config.json"));
  c.audio.grid_features = "pooled";
  EXPECT_THROW(validate(c, "config.json"), Error);
  // A config.json written before the key existed is the published design.
  nlohmann::json j = to_json(train_preset("cpu"));
  j["audio"].erase("grid_features");
  EXPECT_EQ(train_config_from_json(j, "config.json").audio.grid_features, "global");
}

TEST(TrainConfig, DecayHeadsRoundTripAndDefaultOff) {
  TrainConfig c = train_preset("cpu");
  c.audio.decay_heads = true;
  EXPECT_TRUE(train_config_from_json(to_json(c), "config.json").audio.decay_heads);
  // A config.json written before the key existed has none.
  nlohmann::json j = to_json(train_preset("cpu"));
  j["audio"].erase("decay_heads");
  EXPECT_FALSE(train_config_from_json(j, "config.json").audio.decay_heads);
}

// A config.json edited to a million threads is refused as the flag is (4 x the cores at most).
TEST(TrainConfig, ThreadsAreBoundedAsTheFlag) {
  TrainConfig c = train_preset("cpu");
  c.threads = max_thread_count();
  EXPECT_NO_THROW(validate(c, "config.json"));
  c.threads = 1000000;
  try {
    validate(c, "config.json");
    ADD_FAILURE() << "a million threads must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("config.json.threads: must be from 0"), std::string::npos)
        << e.what();
  }
}

TEST(ResolveTrainConfig, UnknownPresetIsAnError) {
  TrainFlags f;
  f.preset = "gpu";
  try {
    resolve_train_config(f);
    ADD_FAILURE() << "an unknown preset must be refused";
  } catch (const Error& e) {  // names the flag and every preset
    EXPECT_NE(std::string(e.what()).find("--preset"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("reference"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace neraf::infer
