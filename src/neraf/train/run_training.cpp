#include "neraf/train/run_training.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <memory>

#include "neraf/infer/audio_run.h"
#include "neraf/infer/calibration.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/infer/run.h"
#include "neraf/io/atomic_file.h"
#include "neraf/io/folder_lock.h"
#include "neraf/io/json_file.h"
#include "neraf/train/distributed.h"
#include "neraf/train/trainer.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;

namespace neraf::train {

using infer::Modality;
using infer::TrainConfig;

namespace {

std::string run_file(const std::string& run_dir, const char* name) {
  return (fs::path(run_dir) / name).string();
}

// Anything but the folder's lock file (taken before this is asked).
bool folder_has_entries(const fs::path& p) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(p, ec))
    if (entry.path().filename() != io::FolderLock::kFileName) return true;
  return false;
}

// The newest checkpoint whose seal is intact; damaged ones are skipped with a warning (a disk
// error, or bytes changed by hand), so a run resumes from the one before.
std::optional<std::string> newest_intact_checkpoint(const std::string& run_dir) {
  for (const std::string& path : infer::checkpoints_newest_first(run_dir)) {
    const std::string damage = infer::checkpoint_damage(path);
    if (damage.empty()) return path;
    warn(damage + "; resuming from the previous checkpoint instead");
  }
  return std::nullopt;
}

// On resume, the pictures must be those the run was trained on (`was`: its data.json entry).
void check_resumed_images(const nlohmann::json& was, const nlohmann::json& now,
                          const std::string& data_dir) {
  for (const std::string key :
       {"num_train", "height", "width", "train_files", "train_pixels_fnv1a"}) {
    if (key == "train_pixels_fnv1a" && !was.contains(key)) continue;  // a run from before the hash
    require(was.value(key, nlohmann::json()) == now[key],
            data_dir + ": differs from the dataset this run was trained on (" + key +
                "); resume with the original --data");
  }
}

// The calibration stage (infer/calibration.h) of a finished audio/joint run, unless done.
void calibrate_if_needed(const TrainConfig& cfg, const std::string& run_dir,
                         const std::string& checkpoint, int64_t step,
                         const std::vector<const data::RirSet*>& rirs,
                         const std::atomic<bool>* stop) {
  if (cfg.modality == Modality::vision || !cfg.audio.energy_calibration || rirs.empty()) return;
  if (infer::load_calibration(checkpoint, step)) return;
  const auto t0 = std::chrono::steady_clock::now();
  std::string path;
  try {
    path = infer::calibrate_run(run_dir, rirs, checkpoint, stop);
  } catch (const Interrupted&) {
    throw Interrupted("training reached step " + std::to_string(step) +
                      " with its checkpoint saved, but the calibration was stopped; finish it "
                      "with: neraf calibrate --run " +
                      run_dir);
  }
  info("calibrated the acoustic field on its training RIRs in " +
       std::to_string(static_cast<int>(std::lround(
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()))) +
       " s → " + path);
}

// One scene's data: its posed images (for the data manifest and the vision-run check), the
// manifest, and its RIRs (audio/joint).
struct SceneData {
  std::string data_dir;
  data::ImageSet images;
  nlohmann::json manifest;
  std::unique_ptr<data::RirSet> rirs;
  int64_t frames = 0;  // its own frames per RIR (multi-scene: ≤ the run's, to which rirs is padded)
};

data::RirSet load_rirs(const TrainConfig& cfg, const TrainRunOptions& options,
                       const std::string& data_dir, int64_t max_len) {
  data::RirLoadOptions rload;
  rload.progress = options.progress;
  rload.stop = options.stop;              // Ctrl-C stops a feature-cache build too
  rload.cache_dir = cfg.audio.cache_dir;  // --cache-dir, --cache-precision (recorded in config)
  rload.half_precision = data::parse_cache_precision(cfg.audio.cache_precision);
  rload.max_len = max_len;  // --max-len, else automatic (published or longest train)
  return data::load_rir_set(data_dir, rload);
}

// The scenes of a multi-scene run (cfg.audio.vision_runs[s] is scene s's vision run), each checked
// against its vision run, all of one layout, sample rate and STFT, and all with the same frames
// per RIR: without --max-len the longest scene's automatic value, recorded in cfg.audio.max_len so
// resume and eval load the same features. Each scene keeps its own automatic length as
// SceneData::frames (its manifest's audio.scene_frames): training draws its frames below it, eval
// and render cut its RIRs to it. `old` is the run's data.json on resume.
std::vector<SceneData> load_scenes(TrainConfig& cfg, const TrainRunOptions& options,
                                   const std::vector<std::string>& data_dirs,
                                   const nlohmann::json& old, bool resuming) {
  std::vector<SceneData> scenes;
  const std::vector<std::string> names = infer::name_scenes(data_dirs);
  int64_t longest = 0;
  for (size_t s = 0; s < data_dirs.size(); ++s) {
    SceneData sc;
    sc.data_dir = data_dirs[s];
    data::ImageLoadOptions image_load;
    image_load.progress = options.progress;
    sc.images = data::load_transforms_json(sc.data_dir, image_load);
    sc.manifest = infer::make_data_manifest(sc.images, sc.data_dir);
    // Each scene's grid must come from its own room's field (the one-scene run's check).
    infer::check_vision_run_data(cfg.audio.vision_runs[s], sc.manifest);
    sc.rirs =
        std::make_unique<data::RirSet>(load_rirs(cfg, options, sc.data_dir, cfg.audio.max_len));
    if (s > 0) {
      const nlohmann::json a = infer::make_audio_manifest(*scenes.front().rirs),
                           b = infer::make_audio_manifest(*sc.rirs);
      for (const char* key :
           {"layout", "sample_rate", "channels", "n_fft", "win_length", "hop_length", "n_freq"})
        require(a[key] == b[key], "--data " + sc.data_dir + ": its " + key + " (" + b[key].dump() +
                                      ") differs from --data " + scenes.front().data_dir + "'s (" +
                                      a[key].dump() +
                                      "); one multi-scene run needs scenes of one layout, sample "
                                      "rate and STFT: synthesise or convert them alike");
    }
    longest = std::max(longest, sc.rirs->max_len);
    sc.frames = sc.rirs->max_len;
    scenes.push_back(std::move(sc));
  }
  if (cfg.audio.max_len == 0)
    for (SceneData& sc : scenes)
      if (sc.rirs->max_len != longest) {
        // Padded with the floor value past each RIR's end, as a shorter RIR is in any one scene.
        sc.rirs = std::make_unique<data::RirSet>(load_rirs(cfg, options, sc.data_dir, longest));
        cfg.audio.max_len = longest;
      }
  for (size_t s = 0; s < scenes.size(); ++s) {
    SceneData& sc = scenes[s];
    if (resuming && infer::is_multiscene(old)) {
      require(old["scenes"].size() == scenes.size(),
              "--data: this run was trained on " + std::to_string(old["scenes"].size()) +
                  " scenes; resume with its own --data folders");
      const nlohmann::json& was = old["scenes"][s];
      check_resumed_images(was, sc.manifest, sc.data_dir);
      if (was.contains("audio")) infer::check_audio_manifest(was["audio"], *sc.rirs, sc.data_dir);
      // As it trained (a run from before own lengths: the common length).
      sc.frames = sc.rirs->max_len;
      if (was.contains("audio") && was["audio"].contains("scene_frames")) {
        const nlohmann::json& f = was["audio"]["scene_frames"];
        require(
            f.is_number_integer() && f.get<int64_t>() >= 2 && f.get<int64_t>() <= sc.rirs->max_len,
            options.run_dir + "/data.json: damaged (scene " + names[s] +
                "'s audio.scene_frames); restore it or train a new run");
        sc.frames = f.get<int64_t>();
      }
    }
    sc.manifest["audio"] = infer::make_audio_manifest(*sc.rirs);
    sc.manifest["audio"]["scene_frames"] = sc.frames;
    sc.manifest["name"] = names[s];
  }
  return scenes;
}

}  // namespace

namespace {

// What every rank must share, without what may differ per machine (paths, threads).
std::string comparable_flags(const TrainConfig& cfg, bool resume) {
  if (resume) return nlohmann::json{{"resume", true}}.dump();  // rank 0's config.json is used
  nlohmann::json j = infer::to_json(cfg);
  j.erase("threads");
  if (j.contains("audio") && j["audio"].is_object()) {
    j["audio"].erase("cache_dir");
    j["audio"].erase("vision_run");
  }
  return nlohmann::json{{"resume", false}, {"config", j}}.dump();
}

std::string comparable_manifest(nlohmann::json manifest) {
  manifest.erase("data");  // the dataset's path on each machine
  return manifest.dump();
}

// A new cpu run without --steps: as many audio steps as its data needs (infer::
// fit_run_length_to_data); every rank computes the same from the same data.
// `frames`: each scene's own frames per RIR (empty: its max_len).
void fit_run_length(TrainConfig& cfg, const std::vector<const data::RirSet*>& scenes, bool resume,
                    bool lead, const std::vector<int64_t>& frames = {}) {
  if (resume || scenes.empty()) return;
  int64_t slices = 0;
  for (size_t s = 0; s < scenes.size(); ++s)
    slices += static_cast<int64_t>(
                  infer::audio_train_subset(*scenes[s], cfg.audio.fraction, cfg.seed).size()) *
              (frames.empty() ? scenes[s]->max_len : frames[s]);
  const infer::RunLengthFit fit = infer::fit_run_length_to_data(cfg, slices);
  if (lead && fit.audio_steps_after != fit.audio_steps_before)
    info("cpu preset: " + std::to_string(slices) + " training (RIR, frame) slices, so " +
         std::to_string(fit.audio_steps_after) + " audio steps instead of " +
         std::to_string(fit.audio_steps_before) + " (" + std::to_string(cfg.steps) +
         " steps in all; --steps N sets the length)");
}

// `dist`: null for one process. Rank 0 (or the only process) is the "lead": it alone touches
// the run folder.
TrainRunSummary train_run_folder(const TrainConfig& config_in, const TrainRunOptions& options,
                                 Distributed* dist) {
  const bool lead = !dist || dist->rank() == 0;
  const fs::path run(options.run_dir);
  const std::string config_path = run_file(options.run_dir, "config.json");
  const std::string manifest_path = run_file(options.run_dir, "data.json");
  TrainConfig cfg = config_in;
  std::optional<std::string> resume_from;
  nlohmann::json old_manifest;
  std::unique_ptr<io::FolderLock> lock;
  if (lead) {
    // One writer per run folder; what a killed writer left half-written goes.
    lock = std::make_unique<io::FolderLock>(options.run_dir);
    io::remove_stale_temporaries(options.run_dir);
    io::remove_stale_temporaries(infer::checkpoint_dir(options.run_dir));

    if (options.resume) {
      std::error_code ec;
      require(fs::is_regular_file(config_path, ec),
              options.run_dir +
                  ": no config.json here, so there is no run to resume; drop --resume "
                  "to start a new run");
      cfg = infer::train_config_from_json(io::read_json(config_path), config_path);
      if (options.steps) infer::set_run_length(cfg, *options.steps);
      if (options.threads) cfg.threads = *options.threads;
      if (fs::is_regular_file(manifest_path, ec)) old_manifest = io::read_json(manifest_path);
      infer::check_checkpoint_folder(options.run_dir);
      const bool any = !infer::checkpoints_newest_first(options.run_dir).empty();
      resume_from = newest_intact_checkpoint(options.run_dir);
      require(resume_from || !any,
              options.run_dir + ": every checkpoint is damaged; start over with --force");
      if (!resume_from) warn(options.run_dir + ": no checkpoint yet; starting from step 0");
    } else if (folder_has_entries(run)) {
      std::error_code ec;
      // --force restarts a run; it must not turn any other folder (a dataset, a home folder)
      // into one.
      require(fs::exists(config_path, ec) ||
                  fs::is_directory(infer::checkpoint_dir(options.run_dir), ec),
              options.run_dir +
                  ": not empty and not a neraf run folder (no config.json or checkpoints/); "
                  "choose a new or empty folder for --out");
      require(options.force, options.run_dir +
                                 ": holds a run; pass --resume to continue it or --force to "
                                 "start over (deletes its checkpoints)");
      fs::remove_all(infer::checkpoint_dir(options.run_dir), ec);
      fs::remove(config_path, ec);
      fs::remove(manifest_path, ec);
    }
  }
  if (options.save_every) cfg.save_every = *options.save_every;
  if (dist) {
    // The ranks agree on the flags (or all resume), then train rank 0's resolved config.
    dist->check_same_json("flags", "training config", comparable_flags(cfg, options.resume));
    const std::string rank0 = dist->share_from_rank0("training config", infer::to_json(cfg).dump());
    if (!lead && options.resume) {
      cfg = infer::train_config_from_json(nlohmann::json::parse(rank0), "rank 0's config.json");
      if (options.threads) cfg.threads = *options.threads;
    }
    const int W = dist->world_size();
    if (cfg.modality != Modality::audio)
      require(cfg.rays_per_batch % W == 0, "--rays " + std::to_string(cfg.rays_per_batch) +
                                               ": the global batch must split " +
                                               "evenly over --world-size " + std::to_string(W) +
                                               "; use a multiple of " + std::to_string(W));
    if (cfg.modality != Modality::vision)
      require(cfg.audio.batch_size % W == 0,
              "--world-size " + std::to_string(W) + ": the audio batch of " +
                  std::to_string(cfg.audio.batch_size) +
                  " slices does not split evenly; use a world size that divides it");
  }
  infer::validate(cfg, options.resume ? config_path : "config");
  if (cfg.threads > 0) torch::set_num_threads(cfg.threads);
  torch::manual_seed(cfg.seed);  // anything that still draws from the global generator

  const bool multi = infer::num_scenes(cfg) > 1;
  std::string data_dir = options.data_dir;
  std::vector<SceneData> scenes;
  nlohmann::json manifest;
  std::unique_ptr<data::RirSet> rirs;
  std::unique_ptr<Trainer> trainer;
  std::vector<const data::RirSet*> all_rirs;  // what the calibration stage fits on
  if (multi) {
    require(!dist,
            "--world-size: multi-scene runs do not train data-parallel yet; train them in one "
            "process (without --world-size, or with --world-size 1)");
    std::vector<std::string> dirs = options.scene_data_dirs;
    require(options.data_dir.empty(),
            "--data: this multi-scene run needs one --data per --vision-run (" +
                std::to_string(cfg.audio.vision_runs.size()) +
                "), in the same order; on --resume give them all or none");
    if (dirs.empty() && infer::is_multiscene(old_manifest))
      for (const auto& sc : old_manifest["scenes"]) {
        require(sc.is_object() && sc.contains("data") && sc["data"].is_string(),
                options.run_dir +
                    "/data.json: damaged (a scene without its dataset path); "
                    "restore it or train a new run");
        dirs.push_back(sc["data"].get<std::string>());
      }
    require(dirs.size() == cfg.audio.vision_runs.size(),
            "--data: a multi-scene run needs one --data per --vision-run, in the same order (" +
                std::to_string(dirs.size()) + " --data, " +
                std::to_string(cfg.audio.vision_runs.size()) + " --vision-run)");
    scenes = load_scenes(cfg, options, dirs, old_manifest, resume_from.has_value());
    manifest = {{"format", "neraf-run-data-1"}, {"scenes", nlohmann::json::array()}};
    std::vector<int64_t> frames;
    for (const SceneData& sc : scenes) {
      manifest["scenes"].push_back(sc.manifest);
      all_rirs.push_back(sc.rirs.get());
      frames.push_back(sc.frames);
    }
    fit_run_length(cfg, all_rirs, options.resume, lead, frames);
    trainer = make_multiscene_trainer(cfg, all_rirs, options.device, frames);
  } else {
    require(options.scene_data_dirs.empty(),
            "--data: given " + std::to_string(options.scene_data_dirs.size()) +
                " times but one --vision-run; a multi-scene run needs one --vision-run per --data "
                "(with --modality audio)");
    if (dist && !lead) {
      // After rank 0 has loaded its data (a feature cache in a dataset folder shared by the ranks
      // of one machine is then built once); on resume its data path is the default.
      const nlohmann::json rank0 =
          nlohmann::json::parse(dist->share_from_rank0("data manifest", ""));
      if (data_dir.empty() && rank0.contains("data")) data_dir = rank0["data"];
    }
    if (data_dir.empty() && old_manifest.contains("data")) data_dir = old_manifest["data"];
    require(!data_dir.empty(), "--data: required (the dataset folder or its transforms.json)");
    data::ImageLoadOptions image_load;
    image_load.progress = options.progress && lead;
    scenes.emplace_back();
    scenes.front().images = data::load_transforms_json(data_dir, image_load);
    const data::ImageSet& images = scenes.front().images;
    manifest = infer::make_data_manifest(images, data_dir);
    if (cfg.modality == Modality::audio)
      infer::check_vision_run_data(cfg.audio.vision_run, manifest);  // not another room's field
    if (!old_manifest.is_null() && resume_from) {
      check_resumed_images(old_manifest, manifest, data_dir);
    }
    // The acoustic branch's RIRs (features cached next to the dataset) and their manifest.
    if (cfg.modality != Modality::vision) {
      TrainRunOptions quiet_unless_lead = options;
      quiet_unless_lead.progress = options.progress && lead;
      rirs = std::make_unique<data::RirSet>(
          load_rirs(cfg, quiet_unless_lead, data_dir, cfg.audio.max_len));
      if (!old_manifest.is_null() && resume_from && old_manifest.contains("audio"))
        infer::check_audio_manifest(old_manifest["audio"], *rirs, data_dir);
      manifest["audio"] = infer::make_audio_manifest(*rirs);
      all_rirs.push_back(rirs.get());
    }
    if (dist) {
      if (lead) dist->share_from_rank0("data manifest", manifest.dump());
      dist->check_same_json("data", "dataset", comparable_manifest(manifest));
    }
    fit_run_length(cfg, all_rirs, options.resume, lead);
    trainer = make_trainer(cfg, &images, options.device, rirs.get());
  }
  if (dist) {
    trainer->set_distributed(dist);
    // Every rank resumes from rank 0's checkpoint, read by rank 0 (the others need no access
    // to the run folder).
    const std::string bytes = dist->share_from_rank0(
        "checkpoint", lead && resume_from ? io::read_text_file(*resume_from) : std::string());
    const std::string name =
        dist->share_from_rank0("checkpoint name", resume_from ? *resume_from : std::string());
    if (!bytes.empty()) {
      trainer->load_checkpoint_bytes(bytes, name);
      resume_from = name;
    }
    trainer->broadcast_parameters();
  } else if (resume_from) {
    trainer->load_checkpoint(*resume_from);
  }
  if (lead && resume_from)
    info("resuming " + options.run_dir + " from step " +
         std::to_string(trainer->completed_steps()) + " (" + *resume_from + ")");
  if (lead) {
    // Written only once the checkpoint is known to match, so a refused resume leaves the run as
    // it was.
    io::write_json_atomically(config_path, infer::to_json(cfg));
    io::write_json_atomically(manifest_path, manifest);
  }

  TrainRunSummary summary;
  summary.start_step = trainer->completed_steps();
  summary.end_step = summary.start_step;
  if (summary.start_step >= cfg.steps) {
    if (lead)
      info(options.run_dir + ": already trained to step " + std::to_string(summary.start_step) +
           (options.steps ? "; --steps " + std::to_string(*options.steps) +
                                " is not beyond it, pass a larger --steps to train further"
                          : "; pass --steps N to train further"));
    if (resume_from) {
      summary.checkpoint = *resume_from;
      if (lead)
        calibrate_if_needed(cfg, options.run_dir, *resume_from, summary.start_step, all_rirs,
                            options.stop);
    }
    return summary;
  }

  const std::string what =
      multi ? std::to_string(scenes.size()) + " scenes, " + std::to_string([&] {
                int64_t n = 0;
                for (const auto* r : all_rirs) n += static_cast<int64_t>(r->train.size());
                return n;
              }()) +
                  " train RIRs"
            : std::to_string(scenes.front().images.train.size()) + " train / " +
                  std::to_string(scenes.front().images.eval.size()) + " eval images";
  if (lead)
    info("training " + infer::to_string(cfg.modality) + " (preset " + cfg.preset + ", " + what +
         ", " + std::to_string(torch::get_num_threads()) + " threads" +
         (dist ? " x " + std::to_string(dist->world_size()) + " processes" : std::string()) + ", " +
         nerf::to_string(cfg.model.precision) + " MLPs) → " + options.run_dir);
  Progress progress("train", cfg.steps - summary.start_step,
                    ProgressOptions{"step", 0.2, 10.0, options.progress && lead});
  const auto t0 = std::chrono::steady_clock::now();
  std::deque<double> recent_psnr;
  double psnr_sum = 0, audio_decay = 0;
  int64_t rays = 0;
  for (;;) {
    StepResult r;
    try {
      r = trainer->step();
    } catch (const DivergedError& e) {
      progress.finish();
      throw Error(std::string(e.what()) + "; " +
                  (summary.checkpoint.empty() && !resume_from
                       ? "no checkpoint was written yet"
                       : "the last checkpoint, " +
                             (summary.checkpoint.empty() ? *resume_from : summary.checkpoint) +
                             ", is kept") +
                  "; start over with another --seed, or change the run's settings");
    }
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
    bool stop = options.stop && options.stop->load();
    if (dist) {
      // Ctrl-C on any rank stops every rank after the same step (rank 0 saves it).
      torch::Tensor flag = torch::tensor({stop ? 1.0 : 0.0}, torch::kFloat64);
      dist->sum(flag);
      stop = flag.item<double>() > 0;
    }
    if (lead && (done || stop || r.step % cfg.save_every == 0)) {
      summary.checkpoint = infer::checkpoint_path(options.run_dir, r.step);
      trainer->save_checkpoint(summary.checkpoint);
      infer::prune_checkpoints(options.run_dir, options.keep);
    }
    if (stop) {
      summary.interrupted = true;
      break;
    }
    if (done) break;
  }
  progress.finish();
  if (dist) summary.comm = dist->stats();
  if (summary.interrupted) return summary;  // the caller says so (cli: exit 130)
  if (lead)
    calibrate_if_needed(cfg, options.run_dir, summary.checkpoint, summary.end_step, all_rirs,
                        options.stop);
  return summary;
}

}  // namespace

TrainRunSummary run_training(const TrainConfig& config, const TrainRunOptions& options) {
  // The rendezvous comes first, so an unreachable master or a disagreeing world size is found
  // before any data is read.
  std::unique_ptr<Distributed> dist;
  if (options.distributed.enabled()) dist = std::make_unique<Distributed>(options.distributed);
  if (dist && dist->rank() != 0) return train_run_folder(config, options, dist.get());
  std::error_code ec;
  const bool created = !fs::exists(options.run_dir, ec);
  try {
    return train_run_folder(config, options, dist.get());
  } catch (...) {
    // A refused or failed run leaves no folder behind that it created and wrote no checkpoint to.
    if (created && infer::checkpoints_newest_first(options.run_dir).empty())
      fs::remove_all(options.run_dir, ec);
    else if (!fs::exists(fs::path(options.run_dir) / "config.json", ec))  // not a run: no lock
      fs::remove(fs::path(options.run_dir) / io::FolderLock::kFileName, ec);
    throw;
  }
}

}  // namespace neraf::train
