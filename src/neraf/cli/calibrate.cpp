// `neraf calibrate`: the calibration stage of a run on its own (infer/calibration.h). Training
// runs it at its end; a run stopped before (Ctrl-C, a kill) or an older checkpoint is
// calibrated with this.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/data/rir_set.h"
#include "neraf/infer/calibration.h"
#include "neraf/infer/run.h"
#include "neraf/infer/train_config.h"
#include "neraf/io/folder_lock.h"
#include "neraf/io/json_file.h"
#include "neraf/util/error.h"

namespace neraf::cli {
namespace {

struct CalibrateArgs {
  std::string run_dir;
  std::string data;
  std::string checkpoint;
  bool quiet = false;
  std::string cache_dir, cache_precision;  // "": the run's (RUN/config.json audio.cache_*)
  CLI::Option* cache_dir_opt = nullptr;
};

void run_calibrate(const CalibrateArgs& args) {
  infer::run_config_file(args.run_dir);  // a run this user may read
  // The calibration is written beside the checkpoint: there is no other place to put it.
  require(::access(args.run_dir.c_str(), W_OK) == 0,
          args.run_dir + ": the run folder is not writable (" + std::strerror(errno) +
              "); calibrate writes its file beside the checkpoint, so run it as the run's owner "
              "or on a writable copy of the run");
  require_cache_folder({"--cache-dir", args.cache_dir}, args.run_dir);
  const io::FolderLock lock(args.run_dir);  // not while training writes the run
  const std::string manifest_path = args.run_dir + "/data.json";
  const nlohmann::json manifest = io::read_json(manifest_path);
  const bool multi = infer::is_multiscene(manifest);
  require(multi || (manifest.contains("audio") && manifest.contains("data")),
          manifest_path + ": no audio dataset in this run (trained with --modality vision)");
  data::RirLoadOptions load;
  load.progress = !args.quiet;
  // The cache training used (recorded in its config), unless the flags say otherwise.
  const std::string config_path = args.run_dir + "/config.json";
  const infer::TrainConfig cfg = infer::read_run_config(config_path);
  load.cache_dir = args.cache_dir_opt->count() ? args.cache_dir : cfg.audio.cache_dir;
  load.half_precision = data::parse_cache_precision(
      args.cache_precision.empty() ? cfg.audio.cache_precision : args.cache_precision);
  load.max_len = cfg.audio.max_len;  // as training loaded it (0: automatic)
  std::string path;
  if (multi) {
    // Every scene from the dataset its manifest records (one calibration file holds them all).
    require(args.data.empty(),
            "--data: a multi-scene run records each scene's dataset; drop --data");
    std::vector<data::RirSet> sets;
    for (const auto& scene : manifest["scenes"])
      sets.push_back(data::load_rir_set(scene.value("data", std::string()), load));
    std::vector<const data::RirSet*> scenes;
    for (const auto& r : sets) scenes.push_back(&r);
    path = infer::calibrate_run(args.run_dir, scenes, args.checkpoint);
  } else {
    const std::string data_dir =
        args.data.empty() ? manifest["data"].get<std::string>() : args.data;
    const data::RirSet rirs = data::load_rir_set(data_dir, load);
    path = infer::calibrate_run(args.run_dir, rirs, args.checkpoint);
  }
  std::printf("wrote %s\n", path.c_str());
}

}  // namespace

void register_calibrate(CLI::App& app) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate",
      "Fit a run's energy calibration on its training RIRs (training does this at its end; use "
      "it for a run stopped before, or for an older --checkpoint)");
  cmd->add_option("--run", args->run_dir, "trained run folder (neraf train --out)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--data", args->data,
                  "the run's dataset, if it moved (default: the folder recorded in RUN/data.json)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--checkpoint", args->checkpoint,
                  "a checkpoint file of the run (default: the latest)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--quiet", args->quiet, "No progress bar");
  args->cache_dir_opt = cmd->add_option(
      "--cache-dir", args->cache_dir,
      "folder of the RIR feature cache (default: the one the run was trained with, recorded in "
      "RUN/config.json)");
  cmd->add_option("--cache-precision", args->cache_precision,
                  "feature cache values, fp32 or fp16 (default: the run's)")
      ->check(CLI::IsMember({"fp32", "fp16"}));
  cmd->footer(
      "Writes RUN/checkpoints/step-XXXXXXXXX.calibration.pt beside the checkpoint.\n"
      "Example: neraf calibrate --run runs/demo");
  cmd->callback([args] { run_calibrate(*args); });
}

}  // namespace neraf::cli
