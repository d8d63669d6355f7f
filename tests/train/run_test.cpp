// The run folder end to end on a tiny dataset written in the real nerfstudio layout.
#include "neraf/infer/run.h"

#include <gtest/gtest.h>
#include <torch/torch.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "../infer/synthetic_scene.h"
#include "neraf/eval/evaluation.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/infer/image_output.h"
#include "neraf/io/folder_lock.h"
#include "neraf/io/json_file.h"
#include "neraf/train/run_training.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;
using namespace neraf::train;
using namespace neraf::infer;
using namespace neraf::eval;

namespace {

struct RunTempDir {
  fs::path path;
  explicit RunTempDir(const std::string& tag) {
    path = fs::temp_directory_path() / ("neraf_run_test_" + tag + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~RunTempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// transforms.json + PNGs for the synthetic scene (train_/eval_ file names).
void write_dataset(const fs::path& dir, const neraf::data::ImageSet& set) {
  nlohmann::json frames = nlohmann::json::array();
  auto add = [&](const neraf::data::ImageSplit& s) {
    for (int64_t i = 0; i < s.size(); ++i) {
      const std::string file = "images/" + s.files[static_cast<size_t>(i)];
      write_png((dir / file).string(), s.images[i]);
      nlohmann::json m = nlohmann::json::array();
      for (int r = 0; r < 3; ++r) {
        nlohmann::json row = nlohmann::json::array();
        for (int c = 0; c < 4; ++c) row.push_back(s.camera_to_world[i][r][c].item<double>());
        m.push_back(row);
      }
      m.push_back({0.0, 0.0, 0.0, 1.0});
      frames.push_back({{"file_path", file}, {"transform_matrix", m}});
    }
  };
  add(set.train);
  add(set.eval);
  const auto& k = set.train.intrinsics[0];
  const nlohmann::json t = {{"camera_model", "OPENCV"},
                            {"fl_x", k.fx},
                            {"fl_y", k.fy},
                            {"cx", k.cx},
                            {"cy", k.cy},
                            {"w", k.width},
                            {"h", k.height},
                            {"frames", frames}};
  neraf::io::write_json_atomically((dir / "transforms.json").string(), t);
}

}  // namespace

TEST(Run, TrainResumeRefuseAndLoad) {
  RunTempDir tmp("a");
  const fs::path data = tmp.path / "data", run = tmp.path / "run";
  write_dataset(data, fixtures::make_image_set(3, 12));  // SSIM needs >= 11 px
  TrainConfig cfg = fixtures::tiny_train_config();
  cfg.steps = 4;
  cfg.fields.max_steps = cfg.proposal_networks.max_steps = 4;  // decay over the run (cpu preset)
  cfg.save_every = 2;
  TrainRunOptions o;
  o.data_dir = data.string();
  o.run_dir = run.string();
  o.progress = false;
  const TrainRunSummary s = run_training(cfg, o);
  EXPECT_EQ(s.end_step, 4);
  EXPECT_TRUE(fs::exists(run / "config.json"));
  EXPECT_TRUE(fs::exists(run / "data.json"));
  EXPECT_TRUE(fs::exists(checkpoint_path(run.string(), 2)));
  EXPECT_TRUE(fs::exists(checkpoint_path(run.string(), 4)));

  // A non-empty run folder without --resume/--force is refused.
  EXPECT_THROW(run_training(cfg, o), neraf::Error);

  // Resume to 6 steps.
  TrainRunOptions r = o;
  r.resume = true;
  r.steps = 6;
  const TrainRunSummary s2 = run_training(cfg, r);
  EXPECT_EQ(s2.start_step, 4);
  EXPECT_EQ(s2.end_step, 6);
  EXPECT_EQ(neraf::io::read_json((run / "config.json").string())["steps"], 6);
  // The schedules tied to the run length followed it, and the run still loads its checkpoint.
  EXPECT_EQ(neraf::io::read_json((run / "config.json").string())["fields"]["max_steps"], 6);
  EXPECT_EQ(load_run(run.string()).step, 6);

  // Interrupt flag: stops after one step with a checkpoint.
  std::atomic<bool> stop{true};
  r.steps = 20;
  r.stop = &stop;
  const TrainRunSummary s3 = run_training(cfg, r);
  EXPECT_TRUE(s3.interrupted);
  EXPECT_EQ(s3.end_step, 7);
  EXPECT_TRUE(fs::exists(checkpoint_path(run.string(), 7)));

  // Load for rendering / evaluation.
  LoadedRun lr = load_run(run.string());
  EXPECT_EQ(lr.step, 7);
  EXPECT_FALSE(lr.model->is_training());
  EXPECT_EQ(lr.manifest["num_eval"], 1);
  EXPECT_EQ(manifest_eval_poses(lr.manifest).sizes(), (std::vector<int64_t>{1, 3, 4}));
  const auto images = neraf::data::load_transforms_json(data.string());
  VisionEvalOptions eo;
  eo.progress = false;
  eo.image_dir = (run / "eval").string();
  const VisionEval e = evaluate_vision(lr.model, images.eval, eo);
  EXPECT_EQ(e.n_views, 1);
  EXPECT_TRUE(std::isfinite(e.psnr));
  EXPECT_GT(e.ssim, -1.0);
  EXPECT_TRUE(fs::exists(run / "eval" / "eval_00000.png"));

  // --force starts over.
  TrainRunOptions f = o;
  f.force = true;
  const TrainRunSummary s4 = run_training(cfg, f);
  EXPECT_EQ(s4.start_step, 0);
  EXPECT_FALSE(fs::exists(checkpoint_path(run.string(), 7)));
}

TEST(Run, KeepsTheNewestRefusesASecondWriterAndSkipsDamagedCheckpoints) {
  RunTempDir tmp("keep");
  const fs::path data = tmp.path / "data", run = tmp.path / "run";
  write_dataset(data, fixtures::make_image_set(3, 12));
  TrainConfig cfg = fixtures::tiny_train_config();
  cfg.steps = 6;
  cfg.fields.max_steps = cfg.proposal_networks.max_steps = 6;
  cfg.save_every = 1;
  TrainRunOptions o;
  o.data_dir = data.string();
  o.run_dir = run.string();
  o.progress = false;
  o.keep = 2;
  run_training(cfg, o);
  EXPECT_EQ(checkpoints_newest_first(run.string()),
            (std::vector<std::string>{checkpoint_path(run.string(), 6),
                                      checkpoint_path(run.string(), 5)}));

  TrainRunOptions r = o;
  r.resume = true;
  r.steps = 8;
  {
    const neraf::io::FolderLock other_writer(run.string());
    try {
      run_training(cfg, r);
      FAIL();
    } catch (const neraf::Error& e) {
      EXPECT_NE(std::string(e.what()).find("another neraf process (PID"), std::string::npos)
          << e.what();
    }
  }
  // The newest checkpoint damaged (a changed byte): resume falls back to the one before.
  const std::string newest = checkpoint_path(run.string(), 6);
  {
    std::fstream f(newest, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(newest) / 2));
    f.put('\x7f');
  }
  EXPECT_NE(checkpoint_damage(newest).find("checksum"), std::string::npos);
  const TrainRunSummary s = run_training(cfg, r);
  EXPECT_EQ(s.start_step, 5);
  EXPECT_EQ(s.end_step, 8);
  EXPECT_EQ(checkpoint_damage(checkpoint_path(run.string(), 8)), "");
}
