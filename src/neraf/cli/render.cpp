// `neraf render`: renders from a trained run. `render view` writes a novel view (PNG) and its
// depth; the acoustic branch adds its own `render` subcommands next to it (register them in
// register_render below).
#include <torch/torch.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/cli/render_audio.h"
#include "neraf/infer/run.h"
#include "neraf/render/view.h"
#include "neraf/util/error.h"

namespace neraf::cli {

namespace {

struct ViewArgs {
  std::string run;
  int64_t frame = -1;
  std::string pose;
  std::string out;
  std::string depth;
  std::string checkpoint;
  int threads = 0;
};

void add_render_view(CLI::App& render) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* cmd = render.add_subcommand("view", "Render a view of a trained radiance field (PNG)");
  cmd->footer(
      "--frame I renders the I-th EVAL frame of the run's dataset (0-based, in the order of\n"
      "RUN/data.json \"eval_files\"). --pose FILE renders any camera: a JSON file with\n"
      "\"camera_to_world\" (4x4 or 3x4, OpenGL/nerfstudio convention, in the dataset's own\n"
      "frame like transforms.json) and optional \"intrinsics\" {fx, fy, cx, cy, width, height}\n"
      "(default: the first training camera's).\n"
      "Example: neraf render view --run runs/demo --frame 0 --out view.png --depth depth.png");
  cmd->add_option("--run", args->run, "Run folder made by neraf train")->required();
  CLI::Option* frame =
      cmd->add_option("--frame", args->frame, "Index of the eval frame to render (0-based)")
          ->transform(whole_number(0, 10000000));
  CLI::Option* pose = cmd->add_option("--pose", args->pose, "Camera JSON file (see below)");
  frame->excludes(pose);
  cmd->add_option("--out", args->out, "Output PNG")->required();
  cmd->add_option("--depth", args->depth, "Also write the colour-mapped median depth here (PNG)");
  cmd->add_option("--checkpoint", args->checkpoint,
                  "A specific checkpoint file (default: the run's latest)");
  cmd->add_option("--threads", args->threads,
                  "CPU threads (default: all cores; at most 4 x the cores)")
      ->transform(thread_count());
  cmd->callback([args, frame, pose]() {
    require(frame->count() + pose->count() == 1, "render view: give --frame I or --pose FILE");
    require_safe_output({"--out", args->out}, {{"--depth", args->depth}}, args->run);
    require_safe_output({"--depth", args->depth}, {}, args->run);
    require_extension({"--out", args->out}, ".png");
    if (!args->depth.empty()) require_extension({"--depth", args->depth}, ".png");
    if (args->threads > 0) torch::set_num_threads(args->threads);
    infer::LoadedRun run = infer::load_run(args->run, torch::kCPU, args->checkpoint);
    render::Camera cam;
    if (frame->count()) {
      const int64_t n = run.manifest.at("num_eval").get<int64_t>();
      require(args->frame < n, "--frame " + std::to_string(args->frame) + ": the run has " +
                                   std::to_string(n) + " eval frames (0.." + std::to_string(n - 1) +
                                   ")");
      cam.c2w = infer::manifest_eval_poses(run.manifest)[args->frame];
      cam.intrinsics = infer::manifest_intrinsics(run.manifest, args->frame);
    } else {
      cam = render::read_camera_file(args->pose, run.manifest);
    }
    const render::ViewOutputs o =
        render::render_view(run, cam, args->out, args->depth, run.config.eval_rays_per_chunk);
    std::printf("rendered %dx%d view (step %lld) in %.2f s → %s%s%s\n", cam.intrinsics.width,
                cam.intrinsics.height, static_cast<long long>(run.step), o.seconds,
                args->out.c_str(), args->depth.empty() ? "" : ", depth → ", args->depth.c_str());
  });
}

}  // namespace

void register_render(CLI::App& app) {
  CLI::App* render = app.add_subcommand(
      "render", "Render views, impulse responses (WAV) and loudness maps of a trained run");
  render->require_subcommand(1);
  add_render_view(*render);
  add_render_audio_commands(*render);  // rir, loudness (render_audio.cpp)
}

}  // namespace neraf::cli
