#pragma once
// The Nerfacto model: radiance field + proposal networks + proposal sampler + renderer + losses
// (nerfstudio NerfactoModel with NeRAF's settings). Training vs evaluation follows the module's
// train()/eval() mode: in training the samplers jitter (one random offset per ray) and the
// camera optimizer corrects the rays; in eval the samplers use fixed positions / midpoints.
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include <map>
#include <string>
#include <vector>

#include "neraf/nerf/camera_optimizer.h"
#include "neraf/nerf/config.h"
#include "neraf/nerf/nerfacto_field.h"
#include "neraf/nerf/rays.h"
#include "neraf/nerf/samplers.h"

namespace at {
class Generator;
}

namespace neraf::nerf {

// Named scalar losses; the training objective is their sum.
using LossDict = std::map<std::string, torch::Tensor>;

struct ForwardOptions {
  bool proposal_grad = true;     // run the proposal networks with autograd (update schedule)
  double anneal = 1.0;           // exponent applied to proposal weights before PDF sampling
  at::Generator* gen = nullptr;  // CPU generator for the sampling jitter (training only)
  JitterRows rows;               // the rays' rows in a larger batch (data-parallel training)
};

struct ModelOutputs {
  torch::Tensor rgb;                   // [R, 3] (clamped to [0, 1] in eval mode)
  torch::Tensor accumulation;          // [R]
  torch::Tensor depth;                 // [R] median depth, eval mode only (undefined in training)
  torch::Tensor expected_depth;        // [R] eval mode only
  std::vector<torch::Tensor> weights;  // per level (proposal levels, then nerf): [R, S_k]
  std::vector<torch::Tensor> sdist;    // per level: [R, S_k + 1] spacing-space edges
  std::vector<torch::Tensor> tdist;    // per level: [R, S_k + 1] euclidean edges
};

class NerfactoModelImpl : public torch::nn::Module {
 public:
  NerfactoModelImpl(const ModelConfig& config, int64_t num_train_images, uint64_t seed);

  // rays: origins/directions [R, 3], camera_indices [R] (training image, −1 = none: mean
  // appearance, no pose correction); nears/fars may be undefined (→ the config's planes).
  ModelOutputs forward(RayBundle rays, const ForwardOptions& options = {});

  // rgb_loss (MSE), and in training also interlevel_loss, distortion_loss (already multiplied)
  // and camera_opt_regularizer (when the optimizer is on). gt_rgb: [R, 3] in [0, 1].
  LossDict losses(const ModelOutputs& outputs, const torch::Tensor& gt_rgb);

  // Inference over many rays (no autograd), `chunk` rays at a time: rgb [R,3], depth [R],
  // expected_depth [R], accumulation [R] in the returned outputs (weights lists left empty).
  ModelOutputs render(const RayBundle& rays, int64_t chunk = 1 << 14, double anneal = 1.0);

  // Parameter groups as nerfstudio names them (each gets its own optimizer and LR schedule).
  std::vector<torch::Tensor> field_parameters();     // "fields"
  std::vector<torch::Tensor> proposal_parameters();  // "proposal_networks"
  std::vector<torch::Tensor> camera_parameters();    // "camera_opt" (empty when off)

  void set_precision(Precision p);
  const ModelConfig& config() const { return config_; }
  int64_t num_train_images() const { return num_train_images_; }

  NerfactoField field{nullptr};
  std::vector<ProposalField> proposal_nets;
  CameraOptimizer camera_optimizer{nullptr};

 private:
  ModelConfig config_;
  int64_t num_train_images_;
};
TORCH_MODULE(NerfactoModel);

}  // namespace neraf::nerf
