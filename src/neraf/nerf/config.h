#pragma once
// Configuration of the Nerfacto-style radiance field (one struct per component, defaults = the
// `paper` preset = nerfstudio's `nerfacto` method with NeRAF's overrides, radiance-field-and-cpu.md
// §2 and neraf-reference.md §2.6). `model_preset("cpu")` is the smaller, faster default.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/nerf/config_io.h"
#include "neraf/nerf/hash_grid_kernel.h"

namespace neraf::nerf {

// Precision of the MLP matrix products. bf16: activations and weights are cast to bfloat16 for
// each product (oneDNN AVX-512-bf16 kernels on the CPU, ~10× the fp32 OpenBLAS throughput),
// outputs go back to fp32; the master weights, the hash tables and everything else stay fp32.
// (Upstream Nerfacto trains in fp16 mixed precision on GPUs; bf16 is the CPU analogue.)
enum class Precision { fp32, bf16 };
std::string to_string(Precision p);
// "fp32" | "bf16" | "auto" (auto = bf16 when the CPU has native bf16 instructions, else fp32).
Precision parse_precision(const std::string& name, const std::string& where = "precision");
inline Precision parse_enum(Precision, const std::string& s, const std::string& where) {
  return parse_precision(s, where);
}
// True when /proc/cpuinfo lists avx512_bf16 or amx_bf16 (oneDNN then has native bf16 kernels).
bool cpu_supports_bf16();
Precision default_precision();  // bf16 if cpu_supports_bf16(), else fp32

enum class CameraOptMode { off, SO3xR3 };
std::string to_string(CameraOptMode m);
CameraOptMode parse_enum(CameraOptMode, const std::string& s, const std::string& where);

struct FieldConfig {  // nerfstudio NerfactoField
  HashGridConfig grid{16, 2, 19, 16, 2048};
  int num_layers = 2;  // density MLP: hash → hidden_dim → 1 + geo_feat_dim (1 hidden layer)
  int hidden_dim = 64;
  int geo_feat_dim = 15;
  int num_layers_color = 3;  // colour MLP: SH + geo + appearance → 64 → 64 → 3
  int hidden_dim_color = 64;
  int appearance_dim = 32;
  // Standard deviation of the embeddings' initial values: 1 is torch.nn.Embedding's (nerfstudio).
  // Then every embedding is a distinct random code and their mean, used for held-out views, is
  // unlike any of them: on exposure-stable captures the colour of held-out views shifts. Small
  // initial codes start as one cloud whose mean stays inside it (the cpu preset's 0.01).
  double appearance_init_std = 1.0;
  int sh_degree = 4;                   // 16 direction features
  double average_init_density = 0.01;  // NeRAF / nerfacto preset (model default would be 1.0)
  bool use_average_appearance_embedding = true;  // eval: mean embedding (else zeros)

  template <class V>
  void visit(V& v) {
    v("grid", grid);
    v("num_layers", num_layers);
    v("hidden_dim", hidden_dim);
    v("geo_feat_dim", geo_feat_dim);
    v("num_layers_color", num_layers_color);
    v("hidden_dim_color", hidden_dim_color);
    v("appearance_dim", appearance_dim);
    v("appearance_init_std", appearance_init_std);
    v("sh_degree", sh_degree);
    v("average_init_density", average_init_density);
    v("use_average_appearance_embedding", use_average_appearance_embedding);
  }
};

struct ProposalNetConfig {  // nerfstudio HashMLPDensityField
  HashGridConfig grid{5, 2, 17, 16, 128};
  int num_layers = 2;  // hash → hidden_dim → 1
  int hidden_dim = 16;

  template <class V>
  void visit(V& v) {
    v("grid", grid);
    v("num_layers", num_layers);
    v("hidden_dim", hidden_dim);
  }
};

struct SamplerConfig {  // nerfstudio ProposalNetworkSampler + NearFarCollider
  std::vector<int> proposal_samples{256, 96};  // one entry per proposal network
  int nerf_samples = 48;
  bool single_jitter = true;
  int proposal_update_every = 5;
  int proposal_warmup = 5000;
  bool use_proposal_weight_anneal = true;
  double proposal_weights_anneal_slope = 10.0;
  int proposal_weights_anneal_max_num_iters = 1000;
  double histogram_padding = 0.01;
  double pdf_eps = 1e-5;
  double near_plane = 0.05;
  double far_plane = 1000.0;

  template <class V>
  void visit(V& v) {
    v("proposal_samples", proposal_samples);
    v("nerf_samples", nerf_samples);
    v("single_jitter", single_jitter);
    v("proposal_update_every", proposal_update_every);
    v("proposal_warmup", proposal_warmup);
    v("use_proposal_weight_anneal", use_proposal_weight_anneal);
    v("proposal_weights_anneal_slope", proposal_weights_anneal_slope);
    v("proposal_weights_anneal_max_num_iters", proposal_weights_anneal_max_num_iters);
    v("histogram_padding", histogram_padding);
    v("pdf_eps", pdf_eps);
    v("near_plane", near_plane);
    v("far_plane", far_plane);
  }
};

struct LossConfig {
  double interlevel_loss_mult = 1.0;
  double distortion_loss_mult = 0.002;

  template <class V>
  void visit(V& v) {
    v("interlevel_loss_mult", interlevel_loss_mult);
    v("distortion_loss_mult", distortion_loss_mult);
  }
};

struct CameraOptConfig {  // nerfstudio CameraOptimizerConfig
  CameraOptMode mode = CameraOptMode::SO3xR3;
  double trans_l2_penalty = 1e-2;
  double rot_l2_penalty = 1e-3;

  template <class V>
  void visit(V& v) {
    v("mode", mode);
    v("trans_l2_penalty", trans_l2_penalty);
    v("rot_l2_penalty", rot_l2_penalty);
  }
};

struct ModelConfig {
  FieldConfig field;
  std::vector<ProposalNetConfig> proposal_nets{ProposalNetConfig{{5, 2, 17, 16, 128}, 2, 16},
                                               ProposalNetConfig{{5, 2, 17, 16, 256}, 2, 16}};
  SamplerConfig sampler;
  LossConfig loss;
  CameraOptConfig camera_opt;
  Precision precision = Precision::bf16;  // presets resolve this with default_precision()

  template <class V>
  void visit(V& v) {
    v("field", field);
    v("proposal_nets", proposal_nets);
    v("sampler", sampler);
    v("loss", loss);
    v("camera_opt", camera_opt);
    v("precision", precision);
  }
};

// "paper": exact Nerfacto/NeRAF sizes. "cpu": smaller tables, fewer samples, bounded-room friendly;
// trains the simulator's demo room in minutes on 2 cores. Throws neraf::Error for other names.
ModelConfig model_preset(const std::string& name);
std::vector<std::string> preset_names();  // {"cpu", "paper"}

// Throws neraf::Error("<where>: ...") when a value is out of range (sizes, planes, sample counts).
void validate(const ModelConfig& config, const std::string& where);

}  // namespace neraf::nerf
