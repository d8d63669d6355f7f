#include "neraf/acoustic/resnet3d.h"

#include <torch/torch.h>

#include <string>

#include "neraf/util/error.h"

namespace neraf::acoustic {

namespace nn = torch::nn;

ResNet3dOptions resnet3d_paper_options() { return ResNet3dOptions{}; }

ResNet3dOptions resnet3d_cpu_options() {
  // Sized for a 7×32³ grid on 2 cores: stem 32 ch (k5, s2) → 16³, max pool → 8³, BasicBlocks
  // 64 @ 8³, 128 @ 4³, 256 @ 2³ → 256 features (≈ 1.3 M parameters).
  ResNet3dOptions o;
  o.stem_channels = 32;
  o.block = ResBlock::kBasic;
  o.layers = {1, 1, 1};
  o.planes = {64, 128, 256};
  return o;
}

int64_t resnet3d_min_grid_resolution(const ResNet3dOptions& options) {
  int64_t halvings = 1 + (options.stem_max_pool ? 1 : 0);  // stem conv (stride 2), max pool
  for (int64_t stride : options.strides) halvings += stride == 2 ? 1 : 0;
  // Side after one halving: ceil(S / 2); the last side must be at least 2.
  int64_t side = 2;
  for (int64_t i = 0; i < halvings; ++i) side = 2 * side - 1;
  return side;
}

int64_t resnet3d_expansion(ResBlock block) { return block == ResBlock::kBottleneck ? 4 : 1; }

int64_t resnet3d_out_features(const ResNet3dOptions& options) {
  return options.planes.back() * resnet3d_expansion(options.block);
}

namespace {

nn::Conv3d conv(int64_t in, int64_t out, int64_t kernel, int64_t stride, int64_t padding) {
  return nn::Conv3d(nn::Conv3dOptions(in, out, kernel).stride(stride).padding(padding).bias(false));
}

// BatchNorm over the one grid of a batch: with that grid's own statistics in train AND eval mode
// (no running statistics; see resnet3d.h for why), or, running_stats, as the reference (PyTorch's
// defaults: running statistics in eval mode, momentum 0.1, eps 1e-5).
nn::BatchNorm3d make_batch_norm(int64_t channels, bool running_stats) {
  return nn::BatchNorm3d(nn::BatchNorm3dOptions(channels).track_running_stats(running_stats));
}

}  // namespace

ResBlock3dImpl::ResBlock3dImpl(ResBlock kind, int64_t in_channels, int64_t planes, int64_t stride,
                               bool running_stats)
    : kind_(kind) {
  auto batch_norm = [running_stats](int64_t channels) {
    return make_batch_norm(channels, running_stats);
  };
  const int64_t out_channels = planes * resnet3d_expansion(kind);
  if (kind == ResBlock::kBottleneck) {
    conv1 = register_module("conv1", conv(in_channels, planes, 1, 1, 0));
    bn1 = register_module("bn1", batch_norm(planes));
    conv2 = register_module("conv2", conv(planes, planes, 3, stride, 1));
    bn2 = register_module("bn2", batch_norm(planes));
    conv3 = register_module("conv3", conv(planes, out_channels, 1, 1, 0));
    bn3 = register_module("bn3", batch_norm(out_channels));
  } else {
    conv1 = register_module("conv1", conv(in_channels, planes, 3, stride, 1));
    bn1 = register_module("bn1", batch_norm(planes));
    conv2 = register_module("conv2", conv(planes, planes, 3, 1, 1));
    bn2 = register_module("bn2", batch_norm(planes));
  }
  if (stride != 1 || in_channels != out_channels) {
    downsample = register_module(
        "downsample",
        nn::Sequential(conv(in_channels, out_channels, 1, stride, 0), batch_norm(out_channels)));
  }
}

torch::Tensor ResBlock3dImpl::forward(const torch::Tensor& x) {
  auto h = torch::relu(bn1(conv1(x)));
  if (kind_ == ResBlock::kBottleneck) {
    h = torch::relu(bn2(conv2(h)));
    h = bn3(conv3(h));
  } else {
    h = bn2(conv2(h));
  }
  const auto residual = downsample ? downsample->forward(x) : x;
  return torch::relu(h + residual);
}

ResNet3dImpl::ResNet3dImpl(ResNet3dOptions options) : options_(std::move(options)) {
  const auto& o = options_;
  require(o.in_channels >= 1 && o.stem_channels >= 1 && o.stem_kernel >= 1,
          "resnet3d: channels and stem kernel must be positive");
  require(!o.layers.empty() && o.layers.size() == o.planes.size() &&
              o.layers.size() == o.strides.size(),
          "resnet3d: layers, planes and strides must be non-empty and of equal length");
  conv1 = register_module(
      "conv1", conv(o.in_channels, o.stem_channels, o.stem_kernel, 2, o.stem_kernel / 2));
  bn1 = register_module("bn1", make_batch_norm(o.stem_channels, o.running_stats));
  int64_t in = o.stem_channels;
  for (size_t s = 0; s < o.layers.size(); ++s) {
    require(o.layers[s] >= 1 && o.planes[s] >= 1 && o.strides[s] >= 1,
            "resnet3d: blocks, planes and strides must be positive");
    nn::Sequential stage;
    for (int64_t b = 0; b < o.layers[s]; ++b) {
      stage->push_back(
          ResBlock3d(o.block, in, o.planes[s], b == 0 ? o.strides[s] : 1, o.running_stats));
      in = o.planes[s] * resnet3d_expansion(o.block);
    }
    layers_.push_back(register_module("layer" + std::to_string(s + 1), stage));
  }
  // Reference init: xavier_normal_ for every conv, BN weight 1 / bias 0 (also LibTorch's default).
  for (auto& m : modules(/*include_self=*/false)) {
    if (auto* c = m->as<nn::Conv3d>()) {
      nn::init::xavier_normal_(c->weight);
    } else if (auto* bn = m->as<nn::BatchNorm3d>()) {
      nn::init::ones_(bn->weight);
      nn::init::zeros_(bn->bias);
    }
  }
}

namespace {

torch::Tensor global_average(const torch::Tensor& map) {
  return torch::adaptive_avg_pool3d(map, {1, 1, 1}).flatten(1);  // [B, C]
}

}  // namespace

torch::Tensor ResNet3dImpl::stem(const torch::Tensor& x) {
  TORCH_CHECK(x.dim() == 5 && x.size(1) == options_.in_channels, "ResNet3d: expected [B, ",
              options_.in_channels, ", S, S, S], got ", x.sizes());
  return torch::relu(bn1(conv1(x)));
}

std::pair<torch::Tensor, torch::Tensor> ResNet3dImpl::stem_and_map(const torch::Tensor& x) {
  const auto s = stem(x);
  auto h = s;
  if (options_.stem_max_pool) {
    // LibTorch 1.13 has no bf16 max_pool3d on CPU: pool a bf16 map in fp32 (exact: a max).
    const auto dtype = h.scalar_type();
    if (dtype == torch::kBFloat16) h = h.to(torch::kFloat32);
    h = torch::max_pool3d(h, /*kernel_size=*/3, /*stride=*/2, /*padding=*/1).to(dtype);
  }
  for (auto& stage : layers_) h = stage->forward(h);
  return {s, h};
}

torch::Tensor ResNet3dImpl::feature_map(const torch::Tensor& x) { return stem_and_map(x).second; }

std::pair<torch::Tensor, torch::Tensor> ResNet3dImpl::forward_with_stem(const torch::Tensor& x) {
  auto [stem, map] = stem_and_map(x);
  return {stem, global_average(map)};
}

torch::Tensor ResNet3dImpl::forward(const torch::Tensor& x) {
  return global_average(feature_map(x));
}

}  // namespace neraf::acoustic
