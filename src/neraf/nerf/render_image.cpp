#include "neraf/nerf/render_image.h"

#include <torch/torch.h>

#include "neraf/nerf/rays.h"

namespace neraf::nerf {

RenderedImage render_image(NerfactoModel& model, const torch::Tensor& c2w,
                           const data::Intrinsics& k, int64_t chunk, double anneal) {
  const auto device = model->field->grid->table.device();
  const RayBundle rays = camera_rays(c2w.to(device, torch::kFloat32), k);
  const ModelOutputs o = model->render(rays, chunk, anneal);
  const int64_t H = k.height, W = k.width;
  return {o.rgb.view({H, W, 3}), o.depth.view({H, W}), o.expected_depth.view({H, W}),
          o.accumulation.view({H, W})};
}

}  // namespace neraf::nerf
