#pragma once
// Rendering a whole camera image with a trained model (eval mode, no autograd).
#include <torch/types.h>

#include "neraf/data/image_set.h"
#include "neraf/nerf/nerfacto_model.h"

namespace neraf::nerf {

struct RenderedImage {
  torch::Tensor rgb;             // [H, W, 3] float in [0, 1]
  torch::Tensor depth;           // [H, W] median depth (distance along the unit ray direction)
  torch::Tensor expected_depth;  // [H, W]
  torch::Tensor accumulation;    // [H, W]
};

// c2w: [3, 4] in the model's normalised world frame; every pixel centre, `chunk` rays per forward
// pass, mean appearance embedding. anneal: proposal weight exponent (1 after training; ns-eval
// also uses 1).
RenderedImage render_image(NerfactoModel& model, const torch::Tensor& c2w,
                           const data::Intrinsics& intrinsics, int64_t chunk = 1 << 14,
                           double anneal = 1.0);

}  // namespace neraf::nerf
