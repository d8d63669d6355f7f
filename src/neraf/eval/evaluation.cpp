#include "neraf/eval/evaluation.h"

#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "neraf/infer/image_output.h"
#include "neraf/metrics/image_metrics.h"
#include "neraf/nerf/render_image.h"
#include "neraf/util/error.h"
#include "neraf/util/progress.h"

namespace neraf::eval {

namespace {
metrics::ImageView view_of(const torch::Tensor& img) {  // [H, W, 3] float32 contiguous CPU
  return {img.data_ptr<float>(), static_cast<int>(img.size(0)), static_cast<int>(img.size(1)),
          static_cast<int>(img.size(2))};
}
}  // namespace

VisionEval evaluate_vision(nerf::NerfactoModel& model, const data::ImageSplit& eval,
                           const VisionEvalOptions& options) {
  require(eval.size() >= 1, "dataset: the eval split is empty; add eval_ frames to evaluate");
  require(eval.images.defined(), "dataset: eval images were not loaded");
  const auto start = std::chrono::steady_clock::now();
  VisionEval result;
  int64_t n = eval.size();
  if (options.max_views >= 0) n = std::min(n, options.max_views);
  Progress progress("eval", n, ProgressOptions{"view", 0.1, 5.0, options.progress});
  double sum_psnr = 0, sum_ssim = 0;
  for (int64_t i = 0; i < n; ++i) {
    const nerf::RenderedImage r = nerf::render_image(
        model, eval.camera_to_world[i], eval.intrinsics[static_cast<size_t>(i)], options.chunk);
    const torch::Tensor pred = r.rgb.to(torch::kCPU, torch::kFloat32).contiguous();
    const torch::Tensor gt = (eval.images[i].to(torch::kFloat32) / 255.0).contiguous();
    require(gt.sizes() == pred.sizes(),
            eval.files[static_cast<size_t>(i)] + ": image size differs from its intrinsics");
    ViewScore s;
    s.file = eval.files[static_cast<size_t>(i)];
    s.psnr = metrics::psnr(view_of(pred), view_of(gt));
    s.ssim = metrics::ssim(view_of(pred), view_of(gt));
    sum_psnr += s.psnr;
    sum_ssim += s.ssim;
    result.views.push_back(s);
    if (!options.image_dir.empty()) {
      char name[32];
      std::snprintf(name, sizeof name, "eval_%05lld.png", static_cast<long long>(i));
      infer::write_png((std::filesystem::path(options.image_dir) / name).string(),
                       torch::cat({gt, pred}, 1));
    }
    char status[64];
    std::snprintf(status, sizeof status, "PSNR %.2f", sum_psnr / (i + 1));
    progress.update(i + 1, status);
  }
  result.n_views = n;
  result.psnr = n > 0 ? sum_psnr / n : 0;
  result.ssim = n > 0 ? sum_ssim / n : 0;
  progress.finish();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

nlohmann::json to_json(const VisionEval& e) {
  nlohmann::json views = nlohmann::json::array();
  for (const auto& v : e.views)
    views.push_back({{"file", v.file}, {"psnr", v.psnr}, {"ssim", v.ssim}});
  return {{"psnr", e.psnr},
          {"ssim", e.ssim},
          {"n_views", e.n_views},
          {"views", views},
          {"seconds", e.seconds}};
}

}  // namespace neraf::eval
