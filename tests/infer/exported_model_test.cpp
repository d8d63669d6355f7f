// Exporting a run's acoustic field to MODEL.nrf and querying it through neraf_rt: the same
// predictions as the LibTorch path (fp32 to float rounding, bf16 storage within its rounding),
// with the scene feature folded in, for both first-layer layouts (a grid feature or none), and
// clear errors for damaged files.
#include "neraf/infer/exported_model.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "audio_test_util.h"
#include "neraf/infer/calibration.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/io/json_file.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"

namespace neraf::infer {
namespace {

using fixtures::make_image_set;
using fixtures::make_temp_dir;
using fixtures::tiny_joint_config;
using fixtures::tiny_rir_set;

// A run folder trained for two steps with `config` on the tiny scene.
std::string make_run(const std::string& dir, const data::RirSet& rirs, const TrainConfig& c) {
  torch::manual_seed(0);
  const data::ImageSet images = make_image_set();
  const std::string run_dir = dir + "/run_" + c.audio.grid;
  {
    auto trainer = train::make_trainer(c, &images, torch::kCPU, &rirs);
    trainer->step();
    trainer->step();
    trainer->save_checkpoint(checkpoint_path(run_dir, 2));
  }
  io::write_json_atomically(run_dir + "/config.json", to_json(c));
  io::write_json_atomically(run_dir + "/data.json",
                            {{"data", rirs.root}, {"audio", make_audio_manifest(rirs)}});
  calibrate_run(run_dir, rirs);  // the stage training ends with
  return run_dir;
}

// The dataset's poses plus two with the source outside the box: [N, 3], [N, 3], [N].
struct Poses {
  torch::Tensor mic, src, yaw;
};
Poses poses_of(const data::RirSet& rirs) {
  std::vector<double> m, s, y;
  for (const data::Rir& r : rirs.rirs) {
    m.insert(m.end(), {r.mic.x, r.mic.y, r.mic.z});
    s.insert(s.end(), {r.source.x, r.source.y, r.source.z});
    y.push_back(r.heading_deg + 17.0);  // off the trained headings too
  }
  // Sources outside the audio box (as RAF loudspeakers often are): zero position encoding, true
  // relative geometry, in both paths alike.
  const data::Aabb& box = rirs.audio_aabb;
  const data::Rir& first = rirs.rirs.front();
  for (const geometry::Vec3& outside :
       {geometry::Vec3{box.max.x + 2.0, first.source.y, first.source.z},
        geometry::Vec3{box.min.x - 1.5, box.min.y + 0.5, box.max.z + 3.0}}) {
    m.insert(m.end(), {first.mic.x, first.mic.y, first.mic.z});
    s.insert(s.end(), {outside.x, outside.y, outside.z});
    y.push_back(33.0);
  }
  const int64_t n = static_cast<int64_t>(y.size());
  return {torch::tensor(m, torch::kFloat64).view({n, 3}),
          torch::tensor(s, torch::kFloat64).view({n, 3}), torch::tensor(y, torch::kFloat64)};
}

// `check` inspects the loaded run first.
void expect_same_predictions(const std::string& grid, TrainConfig c = tiny_joint_config(),
                             const std::string& tag = "",
                             const std::function<void(const AudioRun&)>& check = {}) {
  const std::string dir = make_temp_dir("export_" + grid + tag);
  const data::RirSet rirs = tiny_rir_set(dir);
  c.audio.grid = grid;
  const AudioRun run = load_audio_run(make_run(dir, rirs, c));
  ASSERT_EQ(run.calibration().defined(), c.audio.energy_calibration);
  if (check) check(run);

  const std::string path = dir + "/model.nrf";
  const ExportReport report = export_model(run, path);
  EXPECT_GT(report.file_bytes, 1000);
  EXPECT_LT(report.max_abs_difference, 1e-4);

  const ExportedModel model = load_exported_model(path);
  EXPECT_EQ(model.info().channels, run.info().channels);
  EXPECT_EQ(model.info().max_len, run.info().max_len);
  EXPECT_EQ(model.info().n_freq, run.info().n_freq);
  EXPECT_EQ(model.info().sample_rate, run.info().sample_rate);
  EXPECT_EQ(model.metadata().at("step").get<int64_t>(), 2);
  EXPECT_EQ(model.metadata().at("data").at("data").get<std::string>(), rirs.root);

  const Poses p = poses_of(rirs);
  const torch::Tensor expected = run.predict_log_stft_batch(p.mic, p.src, p.yaw);
  const torch::Tensor got = model.predict_log_stft_batch(p.mic, p.src, p.yaw);
  ASSERT_EQ(got.sizes(), expected.sizes());
  // Float32 products in another order (BLAS vs LibTorch): rounding only.
  EXPECT_LT((got - expected).abs().max().item<double>(), 1e-4) << grid;
  EXPECT_GT(expected.std().item<double>(), 1e-3);  // not a constant field

  // bf16 storage: the weights rounded to 8 mantissa bits; the predictions stay close (the
  // runtime computes in fp32 unless the CPU has AMX-BF16 or AVX512-BF16).
  ExportOptions bf16;
  bf16.bf16 = true;
  const std::string half = dir + "/model_bf16.nrf";
  const ExportReport half_report = export_model(run, half, bf16);
  EXPECT_LT(half_report.file_bytes, report.file_bytes * 0.75);
  const torch::Tensor rounded =
      load_exported_model(half).predict_log_stft_batch(p.mic, p.src, p.yaw);
  EXPECT_LT((rounded - expected).abs().max().item<double>(), 0.1) << grid;
}

TEST(ExportedModel, SampledGridFoldedIntoTheBiasMatchesLibTorch) {
  expect_same_predictions("sampled");
}

TEST(ExportedModel, NoGridMatchesLibTorch) { expect_same_predictions("none"); }

// The tiny run with preset reference's own options (its ResNet3D-50 and NAcF input, its 18
// viewing directions, BatchNorm with running statistics, no calibration, no relative geometry):
// it trains, its checkpoint holds the running statistics two train-mode steps left, and the export
// folds the eval-mode scene feature (running statistics) so that the runtime matches LibTorch.
TEST(ExportedModel, ReferencePresetTrainsAndExports) {
  TrainConfig c = tiny_joint_config();
  const TrainConfig ref = train_preset("reference");
  c.preset = "reference";
  c.audio.view_directions = ref.audio.view_directions;
  c.audio.resnet_batch_norm = ref.audio.resnet_batch_norm;
  c.audio.energy_calibration = ref.audio.energy_calibration;
  c.audio.relative_geometry = ref.audio.relative_geometry;
  c.audio.position_max_freq_exp = ref.audio.position_max_freq_exp;
  c.audio.early_fraction = ref.audio.early_fraction;
  expect_same_predictions("sampled", c, "_reference", [](const AudioRun& run) {
    const acoustic::AcousticModelOptions& o = run.model()->options();
    EXPECT_EQ(o.grid.view_directions, acoustic::ViewDirections::kReference);
    EXPECT_TRUE(o.resnet.running_stats);
    EXPECT_EQ(o.resnet.block, acoustic::ResBlock::kBottleneck);  // ResNet3D-50
    EXPECT_EQ(o.nacf.in_features(), 1024 + 163);
    const auto buffers = run.model()->named_buffers();
    const torch::Tensor* tracked = buffers.find("resnet3d.bn1.num_batches_tracked");
    ASSERT_NE(tracked, nullptr);
    EXPECT_EQ(tracked->item<int64_t>(), 2);  // one train-mode ResNet3D pass per audio step
  });
}

// A run trained with a bf16 trunk is evaluated in fp32 by default: exactly the numbers of the same
// checkpoint in a run that trained in fp32 (its config.json says fp32; the weights are the same
// fp32 master weights), and not those of --precision bf16.
TEST(AudioRunPrecision, Bf16TrainedRunEvaluatesInFp32ByDefault) {
  const std::string dir = make_temp_dir("precision_bf16");
  const data::RirSet rirs = tiny_rir_set(dir);
  TrainConfig c = tiny_joint_config();
  c.model.precision = nerf::Precision::bf16;
  const std::string run_dir = make_run(dir, rirs, c);
  const std::string as_fp32 = dir + "/as_fp32";
  std::filesystem::copy(run_dir, as_fp32, std::filesystem::copy_options::recursive);
  TrainConfig f = c;
  f.model.precision = nerf::Precision::fp32;
  io::write_json_atomically(as_fp32 + "/config.json", to_json(f));

  const AudioRun trained_bf16 = load_audio_run(run_dir);
  EXPECT_FALSE(trained_bf16.model()->options().nacf.bf16);
  const AudioRun trained_fp32 = load_audio_run(as_fp32);
  const AudioRun asked_bf16 = load_audio_run(run_dir, torch::kCPU, "", nerf::Precision::bf16);
  const Poses p = poses_of(rirs);
  const torch::Tensor a = trained_bf16.predict_log_stft_batch(p.mic, p.src, p.yaw);
  EXPECT_TRUE(torch::equal(a, trained_fp32.predict_log_stft_batch(p.mic, p.src, p.yaw)));
  EXPECT_FALSE(torch::equal(a, asked_bf16.predict_log_stft_batch(p.mic, p.src, p.yaw)));
  // The fp32 export of either is the same field.
  EXPECT_LT(export_model(trained_bf16, dir + "/bf16_trained.nrf").max_abs_difference, 1e-4);
}

// Queries are fp32 by default whatever trained the run (the tiny config trains in fp32 here);
// bf16 on request rounds the trunk's products: close to, not equal to, fp32.
TEST(AudioRunPrecision, Bf16IsTheCallersChoice) {
  const std::string dir = make_temp_dir("precision");
  const data::RirSet rirs = tiny_rir_set(dir);
  const std::string run_dir = make_run(dir, rirs, tiny_joint_config());
  const AudioRun fp32 = load_audio_run(run_dir);
  const AudioRun bf16 = load_audio_run(run_dir, torch::kCPU, "", nerf::Precision::bf16);
  EXPECT_FALSE(fp32.model()->options().nacf.bf16);
  EXPECT_TRUE(bf16.model()->options().nacf.bf16);
  const Poses p = poses_of(rirs);
  const torch::Tensor a = fp32.predict_log_stft_batch(p.mic, p.src, p.yaw);
  const torch::Tensor b = bf16.predict_log_stft_batch(p.mic, p.src, p.yaw);
  const double diff = (a - b).abs().max().item<double>();
  EXPECT_GT(diff, 0.0);
  EXPECT_LT(diff, 0.1);
}

TEST(ExportedModel, DamagedFilesAreOneClearError) {
  const std::string dir = make_temp_dir("export_bad");
  const data::RirSet rirs = tiny_rir_set(dir);
  const AudioRun run = load_audio_run(make_run(dir, rirs, tiny_joint_config()));
  const std::string path = dir + "/model.nrf";
  export_model(run, path);
  const auto size = std::filesystem::file_size(path);

  std::filesystem::copy_file(path, dir + "/cut.nrf");
  std::filesystem::resize_file(dir + "/cut.nrf", size / 2);
  try {
    load_exported_model(dir + "/cut.nrf");
    FAIL() << "a truncated file loaded";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cut.nrf"), std::string::npos) << e.what();
  }
  {
    std::ofstream f(dir + "/foreign.nrf", std::ios::binary);
    f << "RIFF this is not a model file at all, just some bytes of another format";
  }
  EXPECT_THROW(load_exported_model(dir + "/foreign.nrf"), Error);
  EXPECT_THROW(load_exported_model(dir + "/missing.nrf"), Error);
}

}  // namespace
}  // namespace neraf::infer
