#include "neraf/nerf/nerfacto_model.h"

#include <torch/torch.h>

#include "neraf/nerf/losses.h"
#include "neraf/nerf/samplers.h"
#include "neraf/nerf/volume_rendering.h"

namespace neraf::nerf {

NerfactoModelImpl::NerfactoModelImpl(const ModelConfig& config, int64_t num_train_images,
                                     uint64_t seed)
    : config_(config), num_train_images_(num_train_images) {
  validate(config, "model");
  field = register_module(
      "field", NerfactoField(config.field, num_train_images, config.precision, seed * 7919 + 100));
  for (size_t i = 0; i < config.proposal_nets.size(); ++i)
    proposal_nets.push_back(
        register_module("proposal_" + std::to_string(i),
                        ProposalField(config.proposal_nets[i], config.field.average_init_density,
                                      config.precision, seed * 7919 + 200 + 10 * i)));
  camera_optimizer =
      register_module("camera_optimizer", CameraOptimizer(config.camera_opt, num_train_images));
}

void NerfactoModelImpl::set_precision(Precision p) {
  config_.precision = p;
  field->set_precision(p);
  for (auto& net : proposal_nets) net->set_precision(p);
}

namespace {
// Sample positions at the bin midpoints: [R, S, 3].
torch::Tensor sample_positions(const RayBundle& rays, const RaySamples& s) {
  return rays.origins.unsqueeze(1) + rays.directions.unsqueeze(1) * s.midpoints().unsqueeze(2);
}
}  // namespace

ModelOutputs NerfactoModelImpl::forward(RayBundle rays, const ForwardOptions& options) {
  const bool training = is_training();
  const auto& sc = config_.sampler;
  const int64_t R = rays.size();
  const auto fopts = rays.origins.options().dtype(torch::kFloat32);
  if (!rays.nears.defined()) rays.nears = torch::full({R}, sc.near_plane, fopts);
  if (!rays.fars.defined()) rays.fars = torch::full({R}, sc.far_plane, fopts);
  if (!rays.camera_indices.defined())
    rays.camera_indices = torch::full({R}, -1, fopts.dtype(torch::kInt64));
  if (training) rays = camera_optimizer->apply(rays);

  ModelOutputs out;
  // ---- proposal sampling ------------------------------------------------------------------
  RaySamples samples;
  torch::Tensor weights;
  const size_t n_prop = proposal_nets.size();
  for (size_t level = 0; level < n_prop; ++level) {
    const int64_t n = sc.proposal_samples[level];
    if (level == 0)
      samples = uniform_lindisp_samples(rays.nears, rays.fars, n, training, sc.single_jitter,
                                        options.gen, options.rows);
    else
      samples = pdf_samples(samples, torch::pow(weights, options.anneal), rays.nears, rays.fars, n,
                            training, sc.single_jitter, sc.histogram_padding, sc.pdf_eps,
                            options.gen, options.rows);
    torch::Tensor density;
    if (options.proposal_grad && training) {
      density = proposal_nets[level]->forward(sample_positions(rays, samples));
    } else {
      torch::NoGradGuard no_grad;
      density = proposal_nets[level]->forward(sample_positions(rays, samples));
    }
    weights = compute_weights(density, samples.deltas());  // [R, S]
    out.weights.push_back(weights);
    out.sdist.push_back(samples.sdist);
    out.tdist.push_back(samples.tdist);
  }
  samples = pdf_samples(samples, torch::pow(weights, options.anneal), rays.nears, rays.fars,
                        sc.nerf_samples, training, sc.single_jitter, sc.histogram_padding,
                        sc.pdf_eps, options.gen, options.rows);

  // ---- radiance field ---------------------------------------------------------------------
  const auto f =
      field->forward(sample_positions(rays, samples), rays.directions, rays.camera_indices);
  weights = compute_weights(f.density, samples.deltas());
  out.weights.push_back(weights);
  out.sdist.push_back(samples.sdist);
  out.tdist.push_back(samples.tdist);

  out.rgb = composite_rgb(weights, f.rgb);
  out.accumulation = accumulation(weights);
  if (!training) {
    out.rgb = out.rgb.clamp(0.0, 1.0);
    out.depth = median_depth(weights, samples.tdist);
    out.expected_depth = expected_depth(weights, samples.tdist);
  }
  return out;
}

LossDict NerfactoModelImpl::losses(const ModelOutputs& outputs, const torch::Tensor& gt_rgb) {
  LossDict d;
  d["rgb_loss"] = mean_squared_error(outputs.rgb, gt_rgb);
  if (is_training()) {
    d["interlevel_loss"] =
        config_.loss.interlevel_loss_mult * interlevel_loss(outputs.weights, outputs.sdist);
    d["distortion_loss"] = config_.loss.distortion_loss_mult *
                           distortion_loss(outputs.weights.back(), outputs.sdist.back());
    if (camera_optimizer->enabled()) d["camera_opt_regularizer"] = camera_optimizer->regularizer();
  }
  return d;
}

ModelOutputs NerfactoModelImpl::render(const RayBundle& rays, int64_t chunk, double anneal) {
  torch::NoGradGuard no_grad;
  const bool was_training = is_training();
  eval();
  std::vector<torch::Tensor> rgb, depth, expected, acc;
  for (int64_t b = 0; b < rays.size(); b += chunk) {
    const ModelOutputs o =
        forward(rays.slice(b, std::min(rays.size(), b + chunk)), ForwardOptions{false, anneal});
    rgb.push_back(o.rgb);
    depth.push_back(o.depth);
    expected.push_back(o.expected_depth);
    acc.push_back(o.accumulation);
  }
  if (was_training) train();
  ModelOutputs out;
  out.rgb = torch::cat(rgb);
  out.depth = torch::cat(depth);
  out.expected_depth = torch::cat(expected);
  out.accumulation = torch::cat(acc);
  return out;
}

std::vector<torch::Tensor> NerfactoModelImpl::field_parameters() { return field->parameters(); }

std::vector<torch::Tensor> NerfactoModelImpl::proposal_parameters() {
  std::vector<torch::Tensor> p;
  for (auto& net : proposal_nets)
    for (auto& t : net->parameters()) p.push_back(t);
  return p;
}

std::vector<torch::Tensor> NerfactoModelImpl::camera_parameters() {
  return camera_optimizer->parameters();
}

}  // namespace neraf::nerf
