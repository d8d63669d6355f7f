#include "neraf/acoustic/nacf.h"

#include <torch/torch.h>

#include <cmath>

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

NerfEncodingOptions position_encoding(double max_freq_exp) {
  NerfEncodingOptions o;
  o.in_dim = 3;
  o.max_freq_exp = max_freq_exp;
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

torch::Tensor encode_position(const torch::Tensor& p_norm, double max_freq_exp) {
  check_pose_batch(p_norm, "position");
  return nerf_encode(p_norm.to(torch::kFloat64), position_encoding(max_freq_exp))
      .to(torch::kFloat32);
}

torch::Tensor encode_rot(const torch::Tensor& rot) {
  check_pose_batch(rot, "rot");
  return nerf::sh_encode_tcnn_input(rot.to(torch::kFloat64), 4).to(torch::kFloat32);
}

torch::Tensor normalize_to_box(const torch::Tensor& p_m, const std::array<double, 3>& box_min,
                               const std::array<double, 3>& box_max) {
  check_pose_batch(p_m, "position");
  const auto f64 = torch::TensorOptions().dtype(torch::kFloat64).device(p_m.device());
  const auto lo = torch::tensor({box_min[0], box_min[1], box_min[2]}, f64);
  const auto hi = torch::tensor({box_max[0], box_max[1], box_max[2]}, f64);
  const auto q = (p_m.to(torch::kFloat64) - lo) / (hi - lo);
  const auto inside = ((q > 0) & (q < 1)).all(1, /*keepdim=*/true);
  return q * inside.to(torch::kFloat64);
}

torch::Tensor encode_relative_geometry(const torch::Tensor& mic_m, const torch::Tensor& src_m,
                                       const torch::Tensor& rot,
                                       const std::array<double, 3>& extent_m) {
  check_pose_batch(mic_m, "mic");
  check_pose_batch(src_m, "source");
  check_pose_batch(rot, "rot");
  const auto d = src_m.to(torch::kFloat64) - mic_m.to(torch::kFloat64);      // [B, 3] metres
  const auto dx = d.select(1, 0), dy = d.select(1, 1), dz = d.select(1, 2);  // [B]
  const auto dist = d.norm(2, 1).clamp_min(0.05);
  const auto horizontal = (dx * dx + dz * dz).sqrt();
  const auto r = rot.to(torch::kFloat64);
  const auto heading = torch::atan2(2 * r.select(1, 2) - 1, 2 * r.select(1, 0) - 1);
  const auto azimuth = torch::atan2(dz, dx);
  std::vector<torch::Tensor> out;
  for (int k = 1; k <= 3; ++k)
    for (const auto& angle : {azimuth - heading, azimuth + heading}) {
      out.push_back(torch::cos(k * angle));
      out.push_back(torch::sin(k * angle));
    }
  out.push_back(dy / dist);
  out.push_back(horizontal / dist);
  const double diagonal =
      std::sqrt(extent_m[0] * extent_m[0] + extent_m[1] * extent_m[1] + extent_m[2] * extent_m[2]);
  const auto relative_dist = dist / diagonal;
  out.push_back(relative_dist);
  out.push_back(dist.log());
  for (int k = 0; k < 3; ++k) {
    out.push_back(torch::sin(2 * M_PI * std::ldexp(1.0, k) * relative_dist));
    out.push_back(torch::cos(2 * M_PI * std::ldexp(1.0, k) * relative_dist));
  }
  return torch::stack(out, 1).to(torch::kFloat32);  // [B, 22]
}

torch::Tensor nacf_input(const torch::Tensor& grid_feature, const torch::Tensor& t, int64_t max_len,
                         const torch::Tensor& mic_norm, const torch::Tensor& src_norm,
                         const torch::Tensor& rot, double position_max_freq_exp) {
  const int64_t b = t.size(0);
  TORCH_CHECK(mic_norm.size(0) == b && src_norm.size(0) == b && rot.size(0) == b,
              "nacf_input: batch sizes differ (t ", b, ", mic ", mic_norm.size(0), ", src ",
              src_norm.size(0), ", rot ", rot.size(0), ")");
  const auto time = encode_time(t, max_len);                          // [B, 21]
  const auto mic = encode_position(mic_norm, position_max_freq_exp);  // [B, 63]
  const auto src = encode_position(src_norm, position_max_freq_exp);  // [B, 63]
  const auto r = encode_rot(rot);                                     // [B, 16]
  if (!grid_feature.defined()) return torch::cat({mic, src, time, r}, 1);
  auto g = grid_feature.dim() == 1 ? grid_feature.unsqueeze(0) : grid_feature;  // [1|B, G]
  TORCH_CHECK(g.dim() == 2 && (g.size(0) == 1 || g.size(0) == b),
              "nacf_input: grid_feature must be [G], [1, G] or [B, G], got ", grid_feature.sizes());
  g = g.to(torch::kFloat32).expand({b, g.size(1)});
  return torch::cat({g, time, mic, src, r}, 1);  // [B, G + 163]
}

torch::Tensor nacf_input(const NacfOptions& options, const torch::Tensor& grid_feature,
                         const torch::Tensor& t, int64_t max_len, const torch::Tensor& mic_m,
                         const torch::Tensor& src_m, const torch::Tensor& rot,
                         const torch::Tensor& local) {
  std::vector<torch::Tensor> parts = {nacf_input(
      grid_feature, t, max_len, normalize_to_box(mic_m, options.box_min, options.box_max),
      normalize_to_box(src_m, options.box_min, options.box_max), rot,
      options.position_max_freq_exp)};  // [B, G + 163]
  if (options.relative_geometry)
    parts.push_back(encode_relative_geometry(mic_m, src_m, rot, options.extent_m()));  // [B, 22]
  if (options.local_features > 0) {
    TORCH_CHECK(local.defined() && local.dim() == 2 && local.size(0) == t.size(0) &&
                    local.size(1) == options.local_features,
                "nacf_input: local features must be [", t.size(0), ", ", options.local_features,
                "], got ", local.defined() ? local.sizes() : torch::IntArrayRef{});
    parts.push_back(local.to(torch::kFloat32));
  }
  return parts.size() == 1 ? parts.front() : torch::cat(parts, 1);
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
  if (options_.decay_heads) {
    decay_slope = register_module("decay_slope", nn::ModuleList());
    for (int64_t c = 0; c < options_.n_channels; ++c)
      decay_slope->push_back(nn::Linear(in, options_.n_freq));
  }
}

torch::Tensor NacfImpl::forward(const torch::Tensor& h_in) const {
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
  auto out = torch::stack(outs, 1);                                                    // [B, C, F]
  if (options_.decay_heads) {
    outs.clear();
    for (const auto& m : *decay_slope) outs.push_back(m->as<nn::Linear>()->forward(h));  // [B, F]
    const auto tau = h_in.select(1, options_.time_input_column()).to(torch::kFloat32);   // [B]
    out = out + tau.view({-1, 1, 1}) * torch::stack(outs, 1);
  }
  return torch::tanh(out) * options_.output_scale;
}

int64_t NacfImpl::trunk_parameter_count() const {
  int64_t n = 0;
  for (const auto& p : soundfield->parameters()) n += p.numel();
  return n;
}

int64_t NacfImpl::head_parameter_count() const {
  int64_t n = 0;
  for (const auto& p : STFT_linear->parameters()) n += p.numel();
  if (decay_slope)
    for (const auto& p : decay_slope->parameters()) n += p.numel();
  return n;
}

}  // namespace neraf::acoustic
