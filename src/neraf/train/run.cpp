#include "neraf/train/run.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <filesystem>

#include "neraf/io/json_file.h"
#include "neraf/train/audio_run.h"
#include "neraf/train/checkpoint.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;

namespace neraf::train {

namespace {
constexpr const char* kManifestFormat = "neraf-run-data-1";
}  // namespace

nlohmann::json intrinsics_json(const data::Intrinsics& k) {
  return {{"fx", k.fx},       {"fy", k.fy},         {"cx", k.cx}, {"cy", k.cy},
          {"width", k.width}, {"height", k.height}, {"k1", k.k1}, {"k2", k.k2},
          {"k3", k.k3},       {"p1", k.p1},         {"p2", k.p2}};
}

data::Intrinsics intrinsics_from_json(const nlohmann::json& j, const std::string& where) {
  require(j.is_object(), where + ": expected an object with fx, fy, cx, cy, width, height");
  data::Intrinsics k;
  auto num = [&](const char* key, double fallback, bool required) {
    if (!j.contains(key)) {
      require(!required, where + "." + key + ": missing");
      return fallback;
    }
    require(j[key].is_number(), where + "." + key + ": expected a number");
    return j[key].get<double>();
  };
  k.fx = num("fx", 0, true);
  k.fy = num("fy", 0, true);
  k.cx = num("cx", 0, true);
  k.cy = num("cy", 0, true);
  k.width = static_cast<int>(num("width", 0, true));
  k.height = static_cast<int>(num("height", 0, true));
  k.k1 = num("k1", 0, false);
  k.k2 = num("k2", 0, false);
  k.k3 = num("k3", 0, false);
  k.p1 = num("p1", 0, false);
  k.p2 = num("p2", 0, false);
  require(k.fx > 0 && k.fy > 0 && std::isfinite(k.fx) && std::isfinite(k.fy),
          where + ": fx and fy must be positive");
  require(k.width > 0 && k.height > 0 && k.width <= 16384 && k.height <= 16384,
          where + ": width and height must be in 1..16384");
  return k;
}

namespace {

nlohmann::json matrix_json(const torch::Tensor& m) {  // [3, 4]
  const torch::Tensor c = m.to(torch::kFloat64).contiguous();
  nlohmann::json rows = nlohmann::json::array();
  for (int64_t r = 0; r < c.size(0); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int64_t k = 0; k < c.size(1); ++k) row.push_back(c[r][k].item<double>());
    rows.push_back(row);
  }
  return rows;
}

std::string run_file(const std::string& run_dir, const char* name) {
  return (fs::path(run_dir) / name).string();
}

bool folder_has_entries(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec) && fs::directory_iterator(p, ec) != fs::directory_iterator();
}

}  // namespace

nlohmann::json make_data_manifest(const data::ImageSet& images, const std::string& data_dir) {
  std::error_code ec;
  const std::string abs = fs::absolute(data_dir, ec).lexically_normal().string();
  nlohmann::json eval_poses = nlohmann::json::array(), eval_intr = nlohmann::json::array();
  for (int64_t i = 0; i < images.eval.size(); ++i) {
    eval_poses.push_back(matrix_json(images.eval.camera_to_world[i]));
    eval_intr.push_back(intrinsics_json(images.eval.intrinsics[static_cast<size_t>(i)]));
  }
  const data::Intrinsics& k0 = images.train.intrinsics.at(0);
  // Image paths relative to the dataset folder, so the same data read from another working
  // directory (or by absolute path) matches.
  const fs::path root = fs::path(images.source).parent_path();
  auto relative = [&root](const std::vector<std::string>& files) {
    std::vector<std::string> out;
    for (const auto& f : files) out.push_back(fs::path(f).lexically_relative(root).string());
    return out;
  };
  return {{"format", kManifestFormat},
          {"data", abs},
          {"source", images.source},
          {"eval_mode", images.eval_mode},
          {"num_train", images.train.size()},
          {"num_eval", images.eval.size()},
          {"height", k0.height},
          {"width", k0.width},
          {"train_files", relative(images.train.files)},
          {"eval_files", relative(images.eval.files)},
          {"world_transform", matrix_json(images.world_transform)},
          {"world_scale", images.world_scale},
          {"default_intrinsics", intrinsics_json(k0)},
          {"eval_intrinsics", eval_intr},
          {"eval_camera_to_world", eval_poses}};
}

torch::Tensor manifest_eval_poses(const nlohmann::json& m) {
  const auto& poses = m.at("eval_camera_to_world");
  std::vector<double> flat;
  for (const auto& p : poses)
    for (const auto& row : p)
      for (const auto& v : row) flat.push_back(v.get<double>());
  return torch::tensor(flat, torch::kFloat64)
      .view({static_cast<int64_t>(poses.size()), 3, 4})
      .to(torch::kFloat32);
}

data::Intrinsics manifest_intrinsics(const nlohmann::json& m, int64_t eval_index) {
  if (eval_index < 0) return intrinsics_from_json(m.at("default_intrinsics"), "data.json");
  return intrinsics_from_json(m.at("eval_intrinsics").at(static_cast<size_t>(eval_index)),
                              "data.json");
}

TrainRunSummary run_training(const TrainConfig& config_in, const TrainRunOptions& options) {
  const fs::path run(options.run_dir);
  const std::string config_path = run_file(options.run_dir, "config.json");
  const std::string manifest_path = run_file(options.run_dir, "data.json");
  TrainConfig cfg = config_in;
  std::optional<std::string> resume_from;
  nlohmann::json old_manifest;

  if (options.resume) {
    std::error_code ec;
    require(fs::is_regular_file(config_path, ec),
            options.run_dir +
                ": no config.json here, so there is no run to resume; drop --resume "
                "to start a new run");
    cfg = train_config_from_json(io::read_json(config_path), config_path);
    if (options.steps) set_run_length(cfg, *options.steps);
    if (options.threads) cfg.threads = *options.threads;
    if (fs::is_regular_file(manifest_path, ec)) old_manifest = io::read_json(manifest_path);
    resume_from = latest_checkpoint(options.run_dir);
    if (!resume_from) warn(options.run_dir + ": no checkpoint yet; starting from step 0");
  } else if (folder_has_entries(run)) {
    require(options.force, options.run_dir +
                               ": folder is not empty; pass --resume to continue this run or "
                               "--force to start over (deletes its checkpoints)");
    std::error_code ec;
    fs::remove_all(checkpoint_dir(options.run_dir), ec);
    fs::remove(config_path, ec);
    fs::remove(manifest_path, ec);
  }
  validate(cfg, "config");
  if (cfg.threads > 0) torch::set_num_threads(cfg.threads);
  torch::manual_seed(cfg.seed);  // anything that still draws from the global generator

  std::string data_dir = options.data_dir;
  if (data_dir.empty() && old_manifest.contains("data")) data_dir = old_manifest["data"];
  require(!data_dir.empty(), "--data: required (the dataset folder or its transforms.json)");
  const data::ImageSet images = data::load_transforms_json(data_dir);
  nlohmann::json manifest = make_data_manifest(images, data_dir);
  if (!old_manifest.is_null() && resume_from) {
    for (const char* key : {"num_train", "height", "width", "train_files"})
      require(old_manifest.value(key, nlohmann::json()) == manifest[key],
              data_dir + ": differs from the dataset this run was trained on (" + key +
                  "); resume with the original --data");
  }
  // The acoustic branch's RIRs (features cached next to the dataset) and their manifest.
  std::unique_ptr<data::RirSet> rirs;
  if (cfg.modality != Modality::vision) {
    data::RirLoadOptions rload;
    rload.progress = options.progress;
    rirs = std::make_unique<data::RirSet>(data::load_rir_set(data_dir, rload));
    if (!old_manifest.is_null() && resume_from && old_manifest.contains("audio"))
      check_audio_manifest(old_manifest["audio"], *rirs, data_dir);
    manifest["audio"] = make_audio_manifest(*rirs);
  }
  std::unique_ptr<Trainer> trainer = make_trainer(cfg, &images, options.device, rirs.get());
  if (resume_from) {
    trainer->load_checkpoint(*resume_from);
    info("resuming " + options.run_dir + " from step " +
         std::to_string(trainer->completed_steps()) + " (" + *resume_from + ")");
  }
  // Written only once the checkpoint is known to match, so a refused resume leaves the run as
  // it was.
  io::write_json_atomically(config_path, to_json(cfg));
  io::write_json_atomically(manifest_path, manifest);

  TrainRunSummary summary;
  summary.start_step = trainer->completed_steps();
  summary.end_step = summary.start_step;
  if (summary.start_step >= cfg.steps) {
    info(options.run_dir + ": already trained to step " + std::to_string(summary.start_step) +
         "; pass --steps N to train further");
    if (resume_from) summary.checkpoint = *resume_from;
    return summary;
  }

  info("training " + to_string(cfg.modality) + " (preset " + cfg.preset + ", " +
       std::to_string(images.train.size()) + " train / " + std::to_string(images.eval.size()) +
       " eval images, " + std::to_string(torch::get_num_threads()) + " threads, " +
       nerf::to_string(cfg.model.precision) + " MLPs) → " + options.run_dir);
  Progress progress("train", cfg.steps - summary.start_step,
                    ProgressOptions{"step", 0.2, 10.0, options.progress});
  const auto t0 = std::chrono::steady_clock::now();
  std::deque<double> recent_psnr;
  double psnr_sum = 0, audio_decay = 0;
  int64_t rays = 0;
  for (;;) {
    const StepResult r = trainer->step();
    rays += r.rays;
    summary.end_step = r.step;
    summary.last_loss = r.loss;
    if (r.metrics.count("psnr")) {
      recent_psnr.push_back(r.metrics.at("psnr"));
      psnr_sum += recent_psnr.back();
      if (recent_psnr.size() > 50) {
        psnr_sum -= recent_psnr.front();
        recent_psnr.pop_front();
      }
      summary.last_psnr = psnr_sum / recent_psnr.size();
    }
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    summary.seconds = elapsed;
    summary.rays_per_s = elapsed > 0 ? rays / elapsed : 0;
    // Running means of the audio terms (log-magnitude MSE, energy-decay L1).
    auto smooth = [&](const char* key, double& value) {
      if (!r.metrics.count(key)) return;
      const double x = r.metrics.at(key);
      value = value == 0 ? x : 0.98 * value + 0.02 * x;
    };
    smooth("audio_sl", summary.last_audio_sl);
    smooth("audio_decay", audio_decay);
    char status[200];
    int len = std::snprintf(status, sizeof status, "step %lld  loss %.4f",
                            static_cast<long long>(r.step), r.loss);
    if (cfg.modality != Modality::audio)
      len += std::snprintf(status + len, sizeof status - len, "  PSNR %.2f  %.0f rays/s",
                           summary.last_psnr, summary.rays_per_s);
    if (summary.last_audio_sl > 0)
      len += std::snprintf(status + len, sizeof status - len, "  audio SL %.4f",
                           summary.last_audio_sl);
    if (audio_decay > 0)
      std::snprintf(status + len, sizeof status - len, "  decay %.4f", audio_decay);
    progress.update(r.step - summary.start_step, status);

    const bool done = r.step >= cfg.steps;
    const bool stop = options.stop && options.stop->load();
    if (done || stop || r.step % cfg.save_every == 0) {
      summary.checkpoint = checkpoint_path(options.run_dir, r.step);
      trainer->save_checkpoint(summary.checkpoint);
    }
    if (stop) {
      summary.interrupted = true;
      break;
    }
    if (done) break;
  }
  progress.finish();
  if (summary.interrupted)
    info("interrupted: checkpoint saved at step " + std::to_string(summary.end_step) +
         "; continue with --resume");
  return summary;
}

LoadedRun load_run(const std::string& run_dir, torch::Device device,
                   const std::string& checkpoint) {
  std::error_code ec;
  const std::string config_path = run_file(run_dir, "config.json");
  const std::string manifest_path = run_file(run_dir, "data.json");
  require(fs::is_directory(run_dir, ec), run_dir + ": no such run folder; check --run");
  require(fs::is_regular_file(config_path, ec),
          run_dir +
              ": not a training run (no config.json); point --run at a neraf train --out "
              "folder");
  LoadedRun run;
  run.run_dir = run_dir;
  run.config = train_config_from_json(io::read_json(config_path), config_path);
  run.manifest = io::read_json(manifest_path);
  require(run.manifest.value("format", "") == kManifestFormat && run.manifest.contains("num_train"),
          manifest_path + ": not a neraf run data manifest; re-run neraf train");
  if (checkpoint.empty()) {
    const auto latest = latest_checkpoint(run_dir);
    require(latest.has_value(),
            run_dir + ": no checkpoint yet; train first (neraf train --out " + run_dir + ")");
    run.checkpoint = *latest;
  } else {
    run.checkpoint = checkpoint;
  }
  if (run.config.model.precision == nerf::Precision::bf16 && !nerf::cpu_supports_bf16())
    run.config.model.precision = nerf::Precision::fp32;  // same weights, no slow bf16 emulation
  run.model = nerf::NerfactoModel(run.config.model, run.manifest["num_train"].get<int64_t>(),
                                  run.config.seed);
  torch::serialize::InputArchive a;
  load_archive(a, run.checkpoint);
  check_checkpoint_header(a, run.config, run.checkpoint);
  try {
    torch::serialize::InputArchive branch, model;
    a.read("branch_vision", branch);
    branch.read("model", model);
    load_module(*run.model, model, run.checkpoint);
    torch::Tensor step;
    a.read("step", step);
    run.step = step.item<int64_t>();
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    throw Error(run.checkpoint + ": checkpoint does not match the run's config (" +
                what.substr(0, what.find('\n')) + "); it belongs to another run");
  }
  run.model->to(device);
  run.model->eval();
  return run;
}

}  // namespace neraf::train
