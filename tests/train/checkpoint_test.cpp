// Trainer checkpoints: exact resume, broken files and other configs refused, same seed same
// numbers. (Checkpoint names: tests/infer/run_test.cpp.)
#include "neraf/infer/checkpoint.h"

#include <gtest/gtest.h>
#include <torch/torch.h>
#include <unistd.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <limits>

#include "../infer/synthetic_scene.h"
#include "neraf/train/lr_schedule.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;
using namespace neraf::train;
using neraf::infer::Modality;
using neraf::infer::TrainConfig;
namespace fixtures = neraf::infer::fixtures;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("neraf_ckpt_test_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(reinterpret_cast<uintptr_t>(this)));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

std::vector<torch::Tensor> snapshot(Trainer& t) {
  std::vector<torch::Tensor> out;
  for (const auto& p : t.vision()->model()->parameters()) out.push_back(p.detach().clone());
  return out;
}

bool same(const std::vector<torch::Tensor>& a, const std::vector<torch::Tensor>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (!torch::equal(a[i], b[i])) return false;
  return true;
}

}  // namespace

TEST(Checkpoint, SaveLoadRoundTripAndExactResume) {
  const auto images = fixtures::make_image_set();
  const TrainConfig cfg = fixtures::tiny_train_config();
  TempDir d;

  // Uninterrupted: 6 steps.
  auto a = make_trainer(cfg, &images, torch::kCPU);
  for (int i = 0; i < 6; ++i) a->step();

  // Interrupted after 3 steps, reloaded into a fresh trainer, 3 more steps.
  auto b = make_trainer(cfg, &images, torch::kCPU);
  for (int i = 0; i < 3; ++i) b->step();
  b->save_checkpoint(d.file("b.pt"));
  auto c = make_trainer(cfg, &images, torch::kCPU);
  EXPECT_FALSE(same(snapshot(*b), snapshot(*c)));
  c->load_checkpoint(d.file("b.pt"));
  EXPECT_EQ(c->completed_steps(), 3);
  EXPECT_TRUE(same(snapshot(*b), snapshot(*c)));  // round trip equal
  EXPECT_EQ(c->vision()->steps_since_update(), b->vision()->steps_since_update());
  for (int i = 0; i < 3; ++i) c->step();
  // Adam moments, RNG stream and the proposal schedule all resumed: bit-identical.
  EXPECT_TRUE(same(snapshot(*a), snapshot(*c)));
}

TEST(Checkpoint, CorruptedOrTruncatedFileIsAClearError) {
  const auto images = fixtures::make_image_set();
  const TrainConfig cfg = fixtures::tiny_train_config();
  TempDir d;
  auto t = make_trainer(cfg, &images, torch::kCPU);
  t->step();
  t->save_checkpoint(d.file("good.pt"));
  // Truncated copy.
  {
    std::ifstream in(d.file("good.pt"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(d.file("trunc.pt"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    std::string flipped = bytes;
    for (size_t i = bytes.size() / 3; i < bytes.size() / 3 + 64; ++i) flipped[i] ^= 0x5a;
    std::ofstream(d.file("flipped.pt"), std::ios::binary) << flipped;
  }
  std::ofstream(d.file("garbage.pt")) << "this is not a checkpoint";
  for (const char* name : {"trunc.pt", "garbage.pt", "missing.pt"}) {
    auto u = make_trainer(cfg, &images, torch::kCPU);
    try {
      u->load_checkpoint(d.file(name));
      FAIL() << name;
    } catch (const neraf::Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  // Bytes changed anywhere (here in the tensors' data) fail the checksum.
  auto u = make_trainer(cfg, &images, torch::kCPU);
  try {
    u->load_checkpoint(d.file("flipped.pt"));
    FAIL();
  } catch (const neraf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("flipped.pt: damaged (checksum"), std::string::npos)
        << e.what();
  }
}

namespace {
// One parameter and one loss that is NaN or infinite on demand.
class DivergingBranch : public Branch {
 public:
  explicit DivergingBranch(double factor) : factor_(factor) {}
  std::string name() const override { return "diverging"; }
  std::vector<ParamGroup> param_groups() override {
    neraf::infer::ScheduleConfig schedule;
    schedule.lr = 0.1;
    return {{"fields", {weight_}, schedule}};
  }
  LossDict losses(StepContext&) override { return {{"bad_loss", weight_.sum() * factor_}}; }
  void set_training(bool) override {}
  void save(torch::serialize::OutputArchive&) override {}
  void load(torch::serialize::InputArchive&, const std::string&) override {}
  torch::Tensor weight_ = torch::ones({4}).set_requires_grad(true);

 private:
  double factor_;
};
}  // namespace

TEST(Trainer, ANonFiniteLossStopsBeforeTheStepAndNamesTheTerm) {
  TempDir d;
  for (const double factor : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    Trainer t(fixtures::tiny_train_config(), torch::kCPU);
    auto branch = std::make_unique<DivergingBranch>(factor);
    DivergingBranch* b = branch.get();
    t.add_branch(std::move(branch));
    try {
      t.step();
      FAIL();
    } catch (const DivergedError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("step 1: the loss term 'bad_loss' is ") +
                                           (std::isnan(factor) ? "NaN" : "infinite")),
                std::string::npos)
          << e.what();
    }
    EXPECT_TRUE(torch::equal(b->weight_, torch::ones({4})));  // not applied
    EXPECT_EQ(t.completed_steps(), 0);
    // Non-finite weights are never saved.
    {
      torch::NoGradGuard no_grad;
      b->weight_[0] = std::nan("");
    }
    EXPECT_THROW(t.save_checkpoint(d.file("nan.pt")), DivergedError);
    EXPECT_FALSE(fs::exists(d.file("nan.pt")));
  }
}

TEST(Checkpoint, AnotherPresetOrConfigIsRefused) {
  const auto images = fixtures::make_image_set();
  TrainConfig cfg = fixtures::tiny_train_config();
  TempDir d;
  auto t = make_trainer(cfg, &images, torch::kCPU);
  t->save_checkpoint(d.file("c.pt"));

  TrainConfig other = cfg;
  other.preset = "paper";
  auto u = make_trainer(other, &images, torch::kCPU);
  try {
    u->load_checkpoint(d.file("c.pt"));
    FAIL();
  } catch (const neraf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("--preset cpu"), std::string::npos) << e.what();
  }
  TrainConfig bigger = cfg;
  bigger.model.field.hidden_dim = 32;
  auto v = make_trainer(bigger, &images, torch::kCPU);
  try {
    v->load_checkpoint(d.file("c.pt"));
    FAIL();
  } catch (const neraf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("model.field.hidden_dim"), std::string::npos) << e.what();
  }
  // Run length and precision may differ.
  TrainConfig longer = cfg;
  longer.steps = 99;
  longer.model.precision = neraf::nerf::Precision::bf16;
  auto w = make_trainer(longer, &images, torch::kCPU);
  EXPECT_NO_THROW(w->load_checkpoint(d.file("c.pt")));
  // Same config but a dataset with another number of training images: shape mismatch.
  const auto three = fixtures::make_image_set(3);
  auto x = make_trainer(cfg, &three, torch::kCPU);
  EXPECT_THROW(x->load_checkpoint(d.file("c.pt")), neraf::Error);
}

TEST(Trainer, SameSeedSameNumbersAndGroups) {
  const auto images = fixtures::make_image_set();
  const TrainConfig cfg = fixtures::tiny_train_config();
  auto a = make_trainer(cfg, &images, torch::kCPU);
  auto b = make_trainer(cfg, &images, torch::kCPU);
  for (int i = 0; i < 3; ++i) {
    const StepResult ra = a->step(), rb = b->step();
    EXPECT_EQ(ra.loss, rb.loss);
    EXPECT_EQ(ra.step, i + 1);
    EXPECT_TRUE(ra.losses.count("rgb_loss") && ra.losses.count("interlevel_loss") &&
                ra.losses.count("distortion_loss") && ra.losses.count("camera_opt_regularizer"));
    EXPECT_TRUE(ra.metrics.count("psnr"));
    EXPECT_EQ(ra.rays, cfg.rays_per_batch);
  }
  EXPECT_TRUE(same(snapshot(*a), snapshot(*b)));
  EXPECT_NEAR(a->group_lr("fields"), learning_rate(cfg.fields, 3), 1e-15);
  EXPECT_NEAR(a->group_lr("camera_opt"), learning_rate(cfg.camera_opt, 3), 1e-15);
  TrainConfig other = cfg;
  other.seed = 7;
  auto c = make_trainer(other, &images, torch::kCPU);
  c->step();
  EXPECT_FALSE(same(snapshot(*a), snapshot(*c)));
}

TEST(Trainer, AudioModalityIsNotAvailableYet) {
  const auto images = fixtures::make_image_set();
  TrainConfig cfg = fixtures::tiny_train_config();
  cfg.modality = Modality::joint;
  EXPECT_THROW(make_trainer(cfg, &images, torch::kCPU), neraf::Error);
}
