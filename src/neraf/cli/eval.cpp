// `neraf eval`: evaluates a trained run on its held-out data and writes one JSON with a key per
// modality ("vision" here; the acoustic branch adds "audio" in evaluate_run_json below).
#include <torch/torch.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/data/image_set.h"
#include "neraf/io/json_file.h"
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
};

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
      "\"ssim\", \"n_views\", \"views\": [...]}}. Side-by-side GT | prediction PNGs go to\n"
      "RUN/eval/ (or --images DIR).\n"
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
  cmd->callback([args]() {
    if (args->threads > 0) torch::set_num_threads(args->threads);
    train::LoadedRun run = train::load_run(args->run, torch::kCPU, args->checkpoint);
    nlohmann::json out = {{"run", args->run}, {"checkpoint", run.checkpoint}, {"step", run.step}};
    out["vision"] = evaluate_vision_json(run, *args);
    // The acoustic branch: out["audio"] = evaluate_audio_json(run, *args);
    io::write_json_atomically(args->json, out);
  });
}

}  // namespace neraf::cli
