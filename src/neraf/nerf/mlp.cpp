#include "neraf/nerf/mlp.h"

#include <ATen/CPUGeneratorImpl.h>
#include <torch/torch.h>

#include <cmath>

namespace neraf::nerf {

torch::Tensor xavier_uniform(int64_t out_dim, int64_t in_dim, uint64_t seed) {
  auto gen = at::make_generator<at::CPUGeneratorImpl>(seed);
  const double bound = std::sqrt(6.0 / static_cast<double>(in_dim + out_dim));
  return torch::rand({out_dim, in_dim}, gen, torch::kFloat32).mul_(2 * bound).sub_(bound);
}

MlpImpl::MlpImpl(int in_dim, int hidden_dim, int out_dim, int num_layers, Precision precision,
                 uint64_t seed)
    : in_dim_(in_dim), out_dim_(out_dim), precision_(precision) {
  TORCH_CHECK(num_layers >= 1 && in_dim >= 1 && out_dim >= 1 && hidden_dim >= 1,
              "Mlp: invalid sizes");
  for (int l = 0; l < num_layers; ++l) {
    const int64_t i = l == 0 ? in_dim : hidden_dim;
    const int64_t o = l == num_layers - 1 ? out_dim : hidden_dim;
    // Layer seeds derived from the module seed so that layers differ but stay reproducible.
    weights_.push_back(register_parameter("w" + std::to_string(l),
                                          xavier_uniform(o, i, seed * 1000003ULL + l)));
  }
}

torch::Tensor MlpImpl::forward(const torch::Tensor& x) {
  TORCH_CHECK(x.dim() == 2 && x.size(1) == in_dim_, "Mlp: expected [N, ", in_dim_, "] input, got ",
              x.sizes());
  const bool bf16 = precision_ == Precision::bf16;
  torch::Tensor h = bf16 ? x.to(torch::kBFloat16) : x;
  for (size_t l = 0; l < weights_.size(); ++l) {
    const torch::Tensor& w = weights_[l];
    h = torch::nn::functional::linear(h, bf16 ? w.to(torch::kBFloat16) : w);
    if (l + 1 < weights_.size()) h = torch::relu(h);
  }
  return bf16 ? h.to(torch::kFloat32) : h;
}

namespace {
struct TruncExp : public torch::autograd::Function<TruncExp> {
  static torch::Tensor forward(torch::autograd::AutogradContext* ctx, const torch::Tensor& x) {
    ctx->save_for_backward({x});
    return torch::exp(x);
  }
  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grad) {
    const torch::Tensor x = ctx->get_saved_variables()[0];
    return {grad[0] * torch::exp(x.clamp(-15.0, 15.0))};
  }
};
}  // namespace

torch::Tensor trunc_exp(const torch::Tensor& x) { return TruncExp::apply(x); }

}  // namespace neraf::nerf
