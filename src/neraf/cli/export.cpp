// `neraf export`: a trained run's acoustic field as one MODEL.nrf for the neraf_rt runtime.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/exported_model.h"
#include "neraf/util/error.h"

namespace neraf::cli {
namespace {

struct ExportArgs {
  std::string run_dir;
  std::string out_path;
  std::string precision = "fp32";
  std::string checkpoint;
  std::string scene;  // a multi-scene run: the scene exported (its grid feature and box)
};

void run_export(const ExportArgs& args) {
  // An export holds one scene's folded feature and box: a multi-scene run needs --scene.
  const infer::AudioRun run =
      infer::load_audio_run(args.run_dir, torch::kCPU, args.checkpoint, nerf::Precision::fp32,
                            /*calibrated=*/true, infer::scene_flag(args.run_dir, args.scene));
  infer::ExportOptions options;
  options.bf16 = args.precision == "bf16";
  const infer::ExportReport report = infer::export_model(run, args.out_path, options);
  std::printf(
      "wrote %s: %.2f MB (%s weights, step %lld); runtime vs LibTorch on %lld poses: "
      "max |Δ log-STFT| = %.2e\n",
      args.out_path.c_str(), report.file_bytes / 1e6, args.precision.c_str(),
      static_cast<long long>(run.step()), static_cast<long long>(report.poses_checked),
      report.max_abs_difference);
}

}  // namespace

void register_export(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "export",
      "Export a trained run's acoustic field as one model file for the neraf_rt runtime (C API, "
      "no LibTorch): the NAcF weights with the scene feature folded in, the energy calibration, "
      "the audio configuration and the training box. `neraf render rir|loudness`, `auralize` "
      "and `eval` take it with --model.");
  cmd->add_option("--run", args->run_dir, "trained run folder (neraf train --out)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", args->out_path, "model file to write (e.g. room.nrf)")->required();
  cmd->add_option("--precision", args->precision,
                  "weight storage: fp32, or bf16 (about half the size; the runtime computes in "
                  "bf16 where the CPU has AMX-BF16 or AVX512-BF16, else in fp32 with the rounded "
                  "weights)")
      ->check(CLI::IsMember({"fp32", "bf16"}))
      ->capture_default_str();
  cmd->add_option("--checkpoint", args->checkpoint,
                  "a checkpoint file of the run (default: the latest)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--scene", args->scene,
                  "a multi-scene run (neraf train with several --data): the scene to export, by "
                  "name (its dataset folder's) or index; required there, as a model file holds "
                  "one scene");
  cmd->footer(
      "Example:\n  neraf export --run runs/demo --out demo.nrf\n  neraf render rir --model "
      "demo.nrf --mic 2,1.5,1.75 --src 1.1,1.2,0.9 --yaw 90 --out rir.wav");
  cmd->callback([args] {
    require_safe_output({"--out", args->out_path}, {}, args->run_dir);
    require_extension({"--out", args->out_path}, ".nrf");
    run_export(*args);
  });
}

}  // namespace neraf::cli
