#pragma once
// Bias-free ReLU MLP like tiny-cuda-nn's FullyFusedMLP (what Nerfacto runs): weight matrices only,
// Xavier-uniform initialisation from an explicit seed, no output activation. With
// Precision::bf16 each product runs in bfloat16 (fp32 master weights; the input is cast once,
// hidden activations stay bf16, the output is cast back to fp32).
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include <cstdint>
#include <vector>

#include "neraf/nerf/config.h"

namespace neraf::nerf {

class MlpImpl : public torch::nn::Module {
 public:
  // num_layers linear maps: in → hidden (num_layers − 1 times) → out. num_layers = 1: in → out.
  MlpImpl(int in_dim, int hidden_dim, int out_dim, int num_layers, Precision precision,
          uint64_t seed);

  // x: [N, in_dim] float32 → [N, out_dim] float32. One fused autograd node (see mlp.cpp);
  // gradients w.r.t. the weights always, w.r.t. x when x requires grad.
  torch::Tensor forward(const torch::Tensor& x);

  int in_dim() const { return in_dim_; }
  int out_dim() const { return out_dim_; }
  Precision precision() const { return precision_; }
  void set_precision(Precision p) { precision_ = p; }
  const std::vector<torch::Tensor>& weights() const { return weights_; }  // [out_l, in_l] each

 private:
  int in_dim_, out_dim_;
  Precision precision_;
  std::vector<torch::Tensor> weights_;  // registered as "w0", "w1", ...
};
TORCH_MODULE(Mlp);

// The same MLP written with plain LibTorch ops and autograd (the reference the fused op is tested
// against).
torch::Tensor mlp_reference(const torch::Tensor& x, const std::vector<torch::Tensor>& weights,
                            Precision precision);

// exp(x) whose backward clamps x to [−15, 15] (nerfstudio trunc_exp): keeps density gradients
// finite when the raw density drifts far negative or positive.
torch::Tensor trunc_exp(const torch::Tensor& x);

// Xavier-uniform [out, in] matrix from its own generator (independent of the global RNG).
torch::Tensor xavier_uniform(int64_t out_dim, int64_t in_dim, uint64_t seed);

}  // namespace neraf::nerf
