// `neraf eval`: evaluates a trained run on its held-out data and writes one JSON with a key per
// modality ("vision" here; the acoustic branch adds "audio" in evaluate_run_json below).
#include <torch/torch.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "neraf/cli/commands.h"
#include "neraf/data/image_set.h"
#include "neraf/io/json_file.h"
#include "neraf/train/audio_branch.h"
#include "neraf/train/audio_eval.h"
#include "neraf/train/audio_run.h"
#include "neraf/train/evaluation.h"
#include "neraf/train/run.h"
#include "neraf/util/error.h"

namespace neraf::cli {

namespace {

struct EvalArgs {
  std::string run;
  std::string json;
  std::string images;
  std::string data;
  std::string checkpoint;
  int64_t max_views = -1;
  int threads = 0;
  bool no_images = false;
  bool quiet = false;
  bool no_baselines = false;
  bool skip_vision = false;
  int64_t max_rirs = -1;
  std::string ablation_runs;  // comma-separated run folders (e.g. trained with --grid none/zeros)
};

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= s.size()) {
    const size_t end = std::min(s.find(',', start), s.size());
    if (end > start) out.push_back(s.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

// The acoustic field on the test RIRs, with the nearest/linear baselines and optional ablation
// runs (each a run folder of the same dataset; labelled "grid=<mode> (<folder>)").
nlohmann::json evaluate_audio_json(const train::AudioRun& run, const EvalArgs& args) {
  const std::string data_dir =
      args.data.empty() ? run.run().manifest.at("data").get<std::string>() : args.data;
  data::RirLoadOptions load;
  load.progress = !args.quiet;
  const data::RirSet rirs = data::load_rir_set(data_dir, load);
  train::check_audio_manifest(run.run().manifest.at("audio"), rirs, data_dir);
  train::AudioEvalOptions opts;
  opts.progress = !args.quiet;
  opts.max_rirs = args.max_rirs;
  opts.baselines = !args.no_baselines;
  opts.seed = run.run().config.seed;
  opts.out_dir = args.images.empty() ? (std::filesystem::path(args.run) / "eval").string()
                                     : args.images;
  if (args.no_images) opts.num_images = 0;
  const std::vector<int64_t> subset = train::audio_train_subset(
      rirs, run.run().config.audio.fraction, run.run().config.seed);
  train::AudioEval e = train::evaluate_audio(run, rirs, subset, opts);
  nlohmann::json out = train::to_json(e);
  std::vector<train::AudioMethodEval> table = e.methods;
  if (!args.ablation_runs.empty()) {
    nlohmann::json abl = nlohmann::json::object();
    for (const std::string& dir : split_commas(args.ablation_runs)) {
      const train::AudioRun other = train::load_audio_run(dir, torch::kCPU);
      train::check_audio_manifest(other.run().manifest.at("audio"), rirs, dir + "/data.json");
      std::vector<int64_t> test = rirs.test;
      if (args.max_rirs >= 0 && static_cast<int64_t>(test.size()) > args.max_rirs)
        test.resize(static_cast<size_t>(args.max_rirs));
      train::AudioEvalOptions o = opts;
      o.num_images = 0;
      const std::string label = "grid=" + other.run().config.audio.grid + " (" +
                                std::filesystem::path(dir).filename().string() + ")";
      train::AudioMethodEval m = train::evaluate_audio_model(other, rirs, test, label, o);
      abl[label] = train::to_json(m.summary);
      abl[label]["run"] = dir;
      e.methods.push_back(m);
      table.push_back(m);
    }
    out["ablations"] = abl;
  }
  const std::string csv = (std::filesystem::path(opts.out_dir) / "audio_per_rir.csv").string();
  std::filesystem::create_directories(opts.out_dir);
  train::write_audio_csv(csv, e);
  out["grid"] = run.run().config.audio.grid;
  out["per_rir_csv"] = csv;
  std::printf("audio (%s, %zu test RIRs, %.1f s; per-RIR CSV %s):\n%s",
              data::to_string(rirs.layout), e.rir_ids.size(), e.seconds, csv.c_str(),
              train::audio_table(table).c_str());
  return out;
}

nlohmann::json evaluate_vision_json(train::LoadedRun& run, const EvalArgs& args) {
  const std::string data_dir =
      args.data.empty() ? run.manifest.at("data").get<std::string>() : args.data;
  data::ImageLoadOptions load;
  load.progress = !args.quiet;
  const data::ImageSet images = data::load_transforms_json(data_dir, load);
  // The eval cameras must be the ones the run was trained against (same normalisation).
  const nlohmann::json now = train::make_data_manifest(images, data_dir);
  for (const char* key : {"num_train", "eval_files", "world_scale"})
    require(now[key] == run.manifest[key],
            data_dir + ": differs from the dataset the run was trained on (" + key +
                "); pass the original dataset with --data");
  train::VisionEvalOptions opts;
  opts.chunk = run.config.eval_rays_per_chunk;
  opts.max_views = args.max_views;
  opts.progress = !args.quiet;
  if (!args.no_images)
    opts.image_dir = args.images.empty()
                         ? (std::filesystem::path(args.run) / "eval").string()
                         : args.images;
  const train::VisionEval e = train::evaluate_vision(run.model, images.eval, opts);
  std::printf("vision: PSNR %.3f dB  SSIM %.4f  over %lld eval views (%.1f s)%s%s\n", e.psnr,
              e.ssim, static_cast<long long>(e.n_views), e.seconds,
              opts.image_dir.empty() ? "" : "; GT|prediction images in ",
              opts.image_dir.c_str());
  return train::to_json(e);
}

}  // namespace

void register_eval(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "Evaluate a trained run on its held-out views (PSNR, SSIM) and write JSON");
  cmd->footer(
      "PSNR and SSIM follow nerfstudio's evaluation (torchmetrics semantics, mean over the\n"
      "eval views). The JSON has {\"run\", \"checkpoint\", \"step\", \"vision\": {\"psnr\",\n"
      "\"ssim\", \"n_views\", \"views\": [...]}, \"audio\": {\"neraf\"|\"nearest\"|\"linear\":\n"
      "{\"t60_error_pct\", \"c50_error_db\", \"edt_error_s\", \"stft_error\", \"invalid_t60\",\n"
      "\"n_rirs\", \"*_std\"}, \"ablations\"}}. Audio follows NeRAF's evaluator: predicted log-STFT\n"
      "→ Griffin-Lim (32 it., seeded) → T60/C50/EDT vs the measured waveform. Baselines:\n"
      "nearest = the measured RIR of the closest training mic with the same heading and source;\n"
      "linear = inverse-distance blend of the 2-4 closest such training RIRs' magnitudes +\n"
      "Griffin-Lim. Side-by-side GT | prediction PNGs (images: eval_*.png; audio: audio_*.png\n"
      "prediction | GT log-STFT) and audio_per_rir.csv go to RUN/eval/ (or --images DIR).\n"
      "Example: neraf eval --run runs/demo --json runs/demo/eval.json");
  cmd->add_option("--run", args->run, "Run folder made by neraf train")->required();
  cmd->add_option("--json", args->json, "Output JSON file")->required();
  cmd->add_option("--images", args->images, "Folder for the GT|prediction PNGs (default RUN/eval)");
  cmd->add_flag("--no-images", args->no_images, "Do not write the comparison PNGs");
  cmd->add_option("--data", args->data,
                  "Dataset folder (default: the one recorded in RUN/data.json)");
  cmd->add_option("--checkpoint", args->checkpoint,
                  "A specific checkpoint file (default: the run's latest)");
  cmd->add_option("--max-views", args->max_views, "Evaluate only the first N eval views")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads, "CPU threads (default: all cores)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--quiet", args->quiet, "No progress bar");
  cmd->add_flag("--skip-vision", args->skip_vision, "Do not evaluate the images (audio only)");
  cmd->add_flag("--no-baselines", args->no_baselines,
                "Audio: do not score the nearest-neighbour and linear-interpolation baselines");
  cmd->add_option("--max-rirs", args->max_rirs, "Audio: evaluate only the first N test RIRs")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--ablation-runs", args->ablation_runs,
                  "Audio: comma-separated run folders of the same dataset (e.g. trained with "
                  "--grid none / zeros) scored on the same test RIRs and added to the table "
                  "and JSON (audio.ablations)");
  cmd->callback([args]() {
    if (args->threads > 0) torch::set_num_threads(args->threads);
    const std::string config_path = (std::filesystem::path(args->run) / "config.json").string();
    std::error_code ec;
    require(std::filesystem::is_regular_file(config_path, ec),
            args->run + ": not a training run (no config.json); check --run");
    const train::TrainConfig cfg =
        train::train_config_from_json(io::read_json(config_path), config_path);
    nlohmann::json out = {{"run", args->run}};
    if (cfg.modality != train::Modality::vision) {
      const train::AudioRun audio = train::load_audio_run(args->run, torch::kCPU, args->checkpoint);
      out["checkpoint"] = audio.run().checkpoint;
      out["step"] = audio.step();
      out["audio"] = evaluate_audio_json(audio, *args);
    }
    if (!args->skip_vision) {
      // An audio-only run has no radiance field of its own: its --vision-run's is evaluated.
      const bool own = cfg.modality != train::Modality::audio;
      train::LoadedRun run = train::load_run(own ? args->run : cfg.audio.vision_run, torch::kCPU,
                                             own ? args->checkpoint : "");
      if (!out.contains("checkpoint")) {
        out["checkpoint"] = run.checkpoint;
        out["step"] = run.step;
      }
      out["vision"] = evaluate_vision_json(run, *args);
      if (!own) out["vision"]["run"] = cfg.audio.vision_run;
    }
    io::write_json_atomically(args->json, out);
  });
}

}  // namespace neraf::cli
