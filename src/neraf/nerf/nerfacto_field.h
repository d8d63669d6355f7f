#pragma once
// The Nerfacto radiance field (nerfstudio NerfactoField, tcnn semantics):
//   u = (contract(x) + 2)/4 → hash grid [L·F] → density MLP → (raw density, geo features [15])
//   density = average_init_density · trunc_exp(raw)   (0 for samples outside the contracted cube)
//   colour MLP(SH_4(direction) [16], geo [15], appearance embedding [32]) → sigmoid rgb [3]
// Appearance: one learned embedding per training image; index −1 selects the mean embedding
// (what Nerfacto uses for novel views), or zeros if use_average_appearance_embedding is false.
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include <cstdint>

#include "neraf/nerf/config.h"
#include "neraf/nerf/contraction.h"
#include "neraf/nerf/hash_grid.h"
#include "neraf/nerf/mlp.h"

namespace neraf::nerf {

// What the acoustic branch reads from the field (neraf-reference.md §1.4).
struct FieldQuery {
  torch::Tensor density;  // [N] float32, ≥ 0 (0 outside the contracted cube)
  torch::Tensor rgb;      // [N, 3] float32 in (0, 1) (sigmoid)
};

class NerfactoFieldImpl : public torch::nn::Module {
 public:
  NerfactoFieldImpl(const FieldConfig& config, int64_t num_train_images, Precision precision,
                    uint64_t seed);

  // ---- The query interface (used by the acoustic grid sampler) ----------------------------
  // u:          [N, 3] hash-grid input in [0,1]³ (contracted cube: u = (contracted + 2)/4);
  //             points not strictly inside (0,1)³ get density 0.
  // dirs:       [N, 3] view directions fed to the SH encoding as given (unit vectors expected;
  //             nothing is renormalised, as in tcnn).
  // appearance: [N] int64 or a single element (broadcast): a training image index, or −1 for the
  //             mean appearance embedding.
  // Works with or without autograd (wrap in torch::NoGradGuard for pure inference); batch as you
  // like: memory is about 1 KB per point in training mode.
  FieldQuery query(const torch::Tensor& u, const torch::Tensor& dirs,
                   const torch::Tensor& appearance);

  // ---- Along rays (model use) ---------------------------------------------------------------
  struct SampleOutputs {
    torch::Tensor density;  // [R, S]
    torch::Tensor rgb;      // [R, S, 3]
  };
  // positions: [R, S, 3] world (normalised frame); ray_dirs: [R, 3] unit; appearance: [R] int64.
  SampleOutputs forward(const torch::Tensor& positions, const torch::Tensor& ray_dirs,
                        const torch::Tensor& appearance);

  // Density and geo features at already-mapped grid inputs: density [N], geo [N, geo_feat_dim].
  std::pair<torch::Tensor, torch::Tensor> density_and_geo(const GridInput& in);
  // Appearance embeddings for ids [M] (−1 → mean or zeros): [M, appearance_dim].
  torch::Tensor appearance_embedding(const torch::Tensor& ids);

  const FieldConfig& config() const { return config_; }
  int64_t num_train_images() const { return num_train_images_; }
  void set_precision(Precision p);

  HashGrid grid{nullptr};
  Mlp mlp_base{nullptr};                  // L·F → hidden → 1 + geo
  Mlp mlp_head{nullptr};                  // sh + geo + appearance → hidden → hidden → 3
  torch::Tensor embedding_appearance;     // [num_train_images, appearance_dim]

 private:
  // Colour from per-point features: sh [M, 16], geo [M, geo], app [M, A] → [M, 3].
  torch::Tensor color(const torch::Tensor& sh, const torch::Tensor& geo, const torch::Tensor& app);

  FieldConfig config_;
  int64_t num_train_images_;
};
TORCH_MODULE(NerfactoField);

// nerfstudio HashMLPDensityField: hash grid → MLP → average_init_density · trunc_exp.
class ProposalFieldImpl : public torch::nn::Module {
 public:
  ProposalFieldImpl(const ProposalNetConfig& config, double average_init_density,
                    Precision precision, uint64_t seed);
  // positions: [..., 3] world (normalised frame) → density [...]
  torch::Tensor forward(const torch::Tensor& positions);
  void set_precision(Precision p) { mlp->set_precision(p); }

  HashGrid grid{nullptr};
  Mlp mlp{nullptr};

 private:
  double average_init_density_;
};
TORCH_MODULE(ProposalField);

}  // namespace neraf::nerf
