#include "neraf/nerf/nerfacto_field.h"

#include <ATen/CPUGeneratorImpl.h>
#include <torch/torch.h>

#include "neraf/nerf/sh_encoding.h"

namespace neraf::nerf {

NerfactoFieldImpl::NerfactoFieldImpl(const FieldConfig& config, int64_t num_train_images,
                                     Precision precision, uint64_t seed)
    : config_(config), num_train_images_(num_train_images) {
  TORCH_CHECK(num_train_images >= 1, "NerfactoField: need at least one training image");
  grid = register_module("grid", HashGrid(config.grid, seed + 1));
  mlp_base = register_module("mlp_base",
                             Mlp(grid->output_dim(), config.hidden_dim, 1 + config.geo_feat_dim,
                                 config.num_layers, precision, seed + 2));
  const int sh_dim = config.sh_degree * config.sh_degree;
  mlp_head = register_module(
      "mlp_head", Mlp(sh_dim + config.geo_feat_dim + config.appearance_dim, config.hidden_dim_color,
                      3, config.num_layers_color, precision, seed + 3));
  // N(0, appearance_init_std²); torch.nn.Embedding's initialisation is N(0, 1).
  auto gen = at::make_generator<at::CPUGeneratorImpl>(seed + 4);
  embedding_appearance = register_parameter(
      "embedding_appearance",
      torch::randn({num_train_images, config.appearance_dim}, gen, torch::kFloat32) *
          config.appearance_init_std);
}

void NerfactoFieldImpl::set_precision(Precision p) {
  mlp_base->set_precision(p);
  mlp_head->set_precision(p);
}

std::pair<torch::Tensor, torch::Tensor> NerfactoFieldImpl::density_and_geo(const GridInput& in) {
  const torch::Tensor h = mlp_base->forward(grid->forward(in.u));  // [N, 1 + geo]
  const torch::Tensor raw = h.select(1, 0);                        // [N]
  const torch::Tensor geo = h.slice(1, 1);                         // [N, geo]
  const torch::Tensor density =
      trunc_exp(raw) * config_.average_init_density * in.selector.to(torch::kFloat32);
  return {density, geo};
}

torch::Tensor NerfactoFieldImpl::appearance_embedding(const torch::Tensor& ids) {
  const auto ids64 = ids.to(torch::kInt64);
  const torch::Tensor rows = embedding_appearance.index_select(0, ids64.clamp_min(0));  // [M, A]
  const torch::Tensor fallback =
      config_.use_average_appearance_embedding
          ? embedding_appearance.mean(0, /*keepdim=*/true)
          : torch::zeros({1, config_.appearance_dim}, embedding_appearance.options());
  return torch::where((ids64 >= 0).unsqueeze(1), rows, fallback);
}

torch::Tensor NerfactoFieldImpl::color(const torch::Tensor& sh, const torch::Tensor& geo,
                                       const torch::Tensor& app) {
  return torch::sigmoid(mlp_head->forward(torch::cat({sh, geo, app}, 1)));
}

NerfactoFieldImpl::SampleOutputs NerfactoFieldImpl::forward(const torch::Tensor& positions,
                                                            const torch::Tensor& ray_dirs,
                                                            const torch::Tensor& appearance) {
  TORCH_CHECK(positions.dim() == 3 && positions.size(2) == 3, "positions must be [R, S, 3]");
  const int64_t R = positions.size(0), S = positions.size(1);
  const GridInput in = contract_to_grid_input(positions.reshape({R * S, 3}));
  auto [density, geo] = density_and_geo(in);  // [R·S], [R·S, geo]
  // Direction and appearance are constant along a ray: encode once per ray, then broadcast.
  const torch::Tensor sh = sh_encode(ray_dirs, config_.sh_degree);  // [R, 16]
  const torch::Tensor app = appearance_embedding(appearance);       // [R, A]
  const torch::Tensor sh_s = sh.unsqueeze(1).expand({R, S, sh.size(1)}).reshape({R * S, -1});
  const torch::Tensor app_s = app.unsqueeze(1).expand({R, S, app.size(1)}).reshape({R * S, -1});
  const torch::Tensor rgb = color(sh_s, geo, app_s);  // [R·S, 3]
  return {density.view({R, S}), rgb.view({R, S, 3})};
}

FieldQuery NerfactoFieldImpl::query(const torch::Tensor& u, const torch::Tensor& dirs,
                                    const torch::Tensor& appearance) {
  TORCH_CHECK(u.dim() == 2 && u.size(1) == 3, "query: u must be [N, 3], got ", u.sizes());
  TORCH_CHECK(dirs.sizes() == u.sizes(), "query: dirs must be [N, 3] like u, got ", dirs.sizes());
  const int64_t N = u.size(0);
  TORCH_CHECK(appearance.numel() == 1 || appearance.numel() == N,
              "query: appearance must have 1 or N elements");
  const GridInput in = grid_input_from_u(u.to(torch::kFloat32).contiguous());
  auto [density, geo] = density_and_geo(in);
  const torch::Tensor ids = appearance.reshape({-1}).to(u.device());
  torch::Tensor app = appearance_embedding(ids);  // [1 or N, A]
  if (app.size(0) != N) app = app.expand({N, app.size(1)});
  const torch::Tensor sh = sh_encode(dirs.to(torch::kFloat32), config_.sh_degree);
  return {density, color(sh, geo, app)};
}

ProposalFieldImpl::ProposalFieldImpl(const ProposalNetConfig& config, double average_init_density,
                                     Precision precision, uint64_t seed)
    : average_init_density_(average_init_density) {
  grid = register_module("grid", HashGrid(config.grid, seed + 1));
  mlp = register_module(
      "mlp", Mlp(grid->output_dim(), config.hidden_dim, 1, config.num_layers, precision, seed + 2));
}

torch::Tensor ProposalFieldImpl::forward(const torch::Tensor& positions) {
  const auto shape = positions.sizes().vec();
  const GridInput in = contract_to_grid_input(positions.reshape({-1, 3}));
  const torch::Tensor raw = mlp->forward(grid->forward(in.u)).select(1, 0);  // [N]
  const torch::Tensor density =
      trunc_exp(raw) * average_init_density_ * in.selector.to(torch::kFloat32);
  return density.view(std::vector<int64_t>(shape.begin(), shape.end() - 1));
}

}  // namespace neraf::nerf
