#pragma once
// Evaluation of a trained run on the held-out views (nerfstudio's get_average_eval_image_metrics:
// per-view PSNR and SSIM with torchmetrics semantics, averaged over the views).
// The eval JSON has one key per modality: "vision" here; the acoustic branch adds "audio" with
// its own evaluate_* function, next to evaluate_vision, and cli/eval.cpp merges them.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/data/image_set.h"
#include "neraf/nerf/nerfacto_model.h"

namespace neraf::eval {

struct ViewScore {
  std::string file;  // the ground-truth image
  double psnr = 0;
  double ssim = 0;
};

struct VisionEval {
  double psnr = 0;  // mean over views
  double ssim = 0;  // mean over views
  int64_t n_views = 0;
  std::vector<ViewScore> views;
  double seconds = 0;
};

struct VisionEvalOptions {
  int64_t chunk = 16384;   // rays per forward pass
  std::string image_dir;   // if set: <image_dir>/eval_XXXXX.png = GT | prediction side by side
  int64_t max_views = -1;  // evaluate only the first N views (−1: all)
  bool progress = true;
};

// Renders every eval view (mean appearance) and scores it against its ground truth.
VisionEval evaluate_vision(nerf::NerfactoModel& model, const data::ImageSplit& eval,
                           const VisionEvalOptions& options = {});

nlohmann::json to_json(const VisionEval& e);  // {"psnr", "ssim", "n_views", "views": [...]}

}  // namespace neraf::eval
