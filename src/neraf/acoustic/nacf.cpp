#include "neraf/acoustic/nacf.h"

#include <torch/torch.h>

#include "neraf/acoustic/positional_encoding.h"
#include "neraf/nerf/sh_encoding.h"
#include "neraf/util/error.h"

namespace neraf::acoustic {

namespace nn = torch::nn;

NacfOptions nacf_paper_options(int64_t n_channels, int64_t n_freq, int64_t grid_features) {
  NacfOptions o;
  o.grid_features = grid_features;
  o.n_channels = n_channels;
  o.n_freq = n_freq;
  return o;
}

NacfOptions nacf_cpu_options(int64_t n_channels, int64_t n_freq, int64_t grid_features) {
  NacfOptions o = nacf_paper_options(n_channels, n_freq, grid_features);
  o.trunk = {512, 512, 512, 512, 512};  // the paper's text: 5 layers of 512
  return o;
}

namespace {

NerfEncodingOptions time_encoding() {
  NerfEncodingOptions o;
  o.in_dim = 1;
  return o;
}

NerfEncodingOptions position_encoding() {
  NerfEncodingOptions o;
  o.in_dim = 3;
  return o;
}

void check_pose_batch(const torch::Tensor& x, const char* name) {
  TORCH_CHECK(x.dim() == 2 && x.size(1) == 3, "nacf: ", name, " must be [B, 3], got ", x.sizes());
}

}  // namespace

torch::Tensor encode_time(const torch::Tensor& t, int64_t max_len) {
  TORCH_CHECK(t.dim() == 1, "encode_time: t must be [B], got ", t.sizes());
  require(max_len >= 2, "audio max_len: must be at least 2 frames");
  const auto x = t.to(torch::kFloat32).div(static_cast<double>(max_len - 1)).unsqueeze(1);  // [B,1]
  return nerf_encode(x, time_encoding());
}

torch::Tensor encode_position(const torch::Tensor& p_norm) {
  check_pose_batch(p_norm, "position");
  return nerf_encode(p_norm.to(torch::kFloat64), position_encoding()).to(torch::kFloat32);
}

torch::Tensor encode_rot(const torch::Tensor& rot) {
  check_pose_batch(rot, "rot");
  return nerf::sh_encode_tcnn_input(rot.to(torch::kFloat64), 4).to(torch::kFloat32);
}

torch::Tensor nacf_input(const torch::Tensor& grid_feature, const torch::Tensor& t, int64_t max_len,
                         const torch::Tensor& mic_norm, const torch::Tensor& src_norm,
                         const torch::Tensor& rot) {
  const int64_t b = t.size(0);
  TORCH_CHECK(mic_norm.size(0) == b && src_norm.size(0) == b && rot.size(0) == b,
              "nacf_input: batch sizes differ (t ", b, ", mic ", mic_norm.size(0), ", src ",
              src_norm.size(0), ", rot ", rot.size(0), ")");
  const auto time = encode_time(t, max_len);   // [B, 21]
  const auto mic = encode_position(mic_norm);  // [B, 63]
  const auto src = encode_position(src_norm);  // [B, 63]
  const auto r = encode_rot(rot);              // [B, 16]
  if (!grid_feature.defined()) return torch::cat({mic, src, time, r}, 1);
  auto g = grid_feature.dim() == 1 ? grid_feature.unsqueeze(0) : grid_feature;  // [1|B, G]
  TORCH_CHECK(g.dim() == 2 && (g.size(0) == 1 || g.size(0) == b),
              "nacf_input: grid_feature must be [G], [1, G] or [B, G], got ", grid_feature.sizes());
  g = g.to(torch::kFloat32).expand({b, g.size(1)});
  return torch::cat({g, time, mic, src, r}, 1);  // [B, G + 163]
}

NacfImpl::NacfImpl(NacfOptions options) : options_(std::move(options)) {
  require(options_.grid_features >= 0, "nacf grid_features: must be >= 0");
  require(!options_.trunk.empty(), "nacf trunk: needs at least one layer");
  require(options_.n_channels >= 1 && options_.n_freq >= 1,
          "nacf: n_channels and n_freq must be positive");
  soundfield = register_module("soundfield", nn::ModuleList());
  int64_t in = options_.in_features();
  for (int64_t width : options_.trunk) {
    require(width >= 1, "nacf trunk: widths must be positive");
    soundfield->push_back(nn::Linear(in, width));
    in = width;
  }
  STFT_linear = register_module("STFT_linear", nn::ModuleList());
  for (int64_t c = 0; c < options_.n_channels; ++c) {
    STFT_linear->push_back(nn::Linear(in, options_.n_freq));
  }
}

torch::Tensor NacfImpl::forward(const torch::Tensor& h_in) {
  TORCH_CHECK(h_in.dim() == 2 && h_in.size(1) == options_.in_features(), "Nacf: expected [B, ",
              options_.in_features(), "], got ", h_in.sizes());
  const auto lowp = torch::kBFloat16;
  auto h = options_.bf16 ? h_in.to(lowp) : h_in;
  for (const auto& m : *soundfield) {
    auto* lin = m->as<nn::Linear>();
    if (options_.bf16) {
      h = torch::linear(h, lin->weight.to(lowp), lin->bias.to(lowp));
    } else {
      h = lin->forward(h);
    }
    h = torch::leaky_relu(h, options_.leaky_slope);
  }
  h = h.to(torch::kFloat32);
  std::vector<torch::Tensor> outs;
  outs.reserve(options_.n_channels);
  for (const auto& m : *STFT_linear) outs.push_back(m->as<nn::Linear>()->forward(h));  // [B, F]
  return torch::tanh(torch::stack(outs, 1)) * options_.output_scale;                   // [B, C, F]
}

int64_t NacfImpl::trunk_parameter_count() const {
  int64_t n = 0;
  for (const auto& p : soundfield->parameters()) n += p.numel();
  return n;
}

int64_t NacfImpl::head_parameter_count() const {
  int64_t n = 0;
  for (const auto& p : STFT_linear->parameters()) n += p.numel();
  return n;
}

}  // namespace neraf::acoustic
