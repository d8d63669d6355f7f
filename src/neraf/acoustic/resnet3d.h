#pragma once
// Scene encoder: a 3D ResNet over the 7×S³ grid → one global feature vector (neraf-reference.md
// §1.5).
//
// Preset paper = the published ResNet3D-50 truncated after layer3: conv1 Conv3d(7→64, k5, s2, p2,
// no bias) → BN → ReLU → MaxPool3d(k3, s2, p1); Bottleneck blocks (expansion 4) [3, 4, 6] with
// planes [64, 128, 256] and strides [1, 2, 2] (stride on the 3×3×3 conv; 1×1×1 conv + BN downsample
// on the first block of a stage) → 1024 channels → global average pool → 1024 features, 17,068,608
// parameters. The reference pools with AvgPool3d(kernel 8, stride 1), which at 128³ input (8³ after
// layer3) is exactly a global average; we use adaptive average pooling to 1³, identical there and
// valid at every grid size. Init: Conv3d xavier_normal_, BN weight 1 / bias 0 (eps 1e-5).
//
// Deliberate change (default; `running_stats = true` restores the reference, preset `reference`):
// BN normalises with the grid's own statistics in train AND eval mode (no running statistics).
// The reference uses running statistics in eval mode (momentum 0.1, updated by every train-mode
// forward), but its batch is one
// grid, so they never equal what training saw: the running variance is the unbiased one over as
// few as 2³ voxels, and in joint training it lags the changing grid. Measured on the demo room:
// the eval-mode scene feature was 11 % off the train-mode one, which lifted every predicted
// late-tail log-magnitude by ~0.2 (a −47 dB floor in the rendered RIR) and tripled the T60 error.
//
// Preset cpu: the same structure with BasicBlocks (two 3×3×3 convs, expansion 1), one block per
// stage, narrower stem — see resnet3d_cpu_options().
//
// Submodule names follow the reference (conv1, bn1, layer1..3 / <block>.conv1, bn1, …,
// downsample.0/1) so a checkpoint importer maps `audio_model.resnet3d.backbone_net.*` names one to
// one.
#include <torch/nn/module.h>
#include <torch/nn/modules/batchnorm.h>
#include <torch/nn/modules/container/sequential.h>
#include <torch/nn/modules/conv.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace neraf::acoustic {

enum class ResBlock { kBasic, kBottleneck };

struct ResNet3dOptions {
  int64_t in_channels = 7;
  int64_t stem_channels = 64;  // conv1 output channels
  int64_t stem_kernel = 5;     // conv1 kernel (stride 2, padding kernel/2)
  bool stem_max_pool = true;   // MaxPool3d(k3, s2, p1) after the stem
  ResBlock block = ResBlock::kBottleneck;
  std::vector<int64_t> layers = {3, 4, 6};       // blocks per stage
  std::vector<int64_t> planes = {64, 128, 256};  // bottleneck width per stage
  std::vector<int64_t> strides = {1, 2, 2};      // stride of each stage's first block
  // BatchNorm as the reference: running statistics (buffers running_mean, running_var,
  // num_batches_tracked; momentum 0.1) used in eval mode. false: the grid's own statistics in
  // both modes, no buffers (ours, see above).
  bool running_stats = false;
};

ResNet3dOptions resnet3d_paper_options();  // ResNet3D-50 truncated after layer3, 1024 features
ResNet3dOptions resnet3d_cpu_options();    // small BasicBlock variant, 256 features

int64_t resnet3d_expansion(ResBlock block);  // 4 for Bottleneck, 1 for Basic
// The smallest grid side S that leaves more than one voxel per channel at the last BatchNorm (the
// stem, the max pool and every strided stage halve the grid, rounding up): 17 for both presets.
int64_t resnet3d_min_grid_resolution(const ResNet3dOptions& options);
int64_t resnet3d_out_features(const ResNet3dOptions& options);

class ResBlock3dImpl : public torch::nn::Module {
 public:
  ResBlock3dImpl(ResBlock kind, int64_t in_channels, int64_t planes, int64_t stride,
                 bool running_stats = false);
  torch::Tensor forward(const torch::Tensor& x);

 private:
  ResBlock kind_;
  torch::nn::Conv3d conv1{nullptr}, conv2{nullptr}, conv3{nullptr};
  torch::nn::BatchNorm3d bn1{nullptr}, bn2{nullptr}, bn3{nullptr};
  torch::nn::Sequential downsample{nullptr};
};
TORCH_MODULE(ResBlock3d);

class ResNet3dImpl : public torch::nn::Module {
 public:
  explicit ResNet3dImpl(ResNet3dOptions options = resnet3d_paper_options());

  // x: [B, in_channels, S, S, S] → [B, out_features]. S must leave > 1 voxel per channel at every
  // BatchNorm in train mode with B = 1 (S ≥ resnet3d_min_grid_resolution).
  torch::Tensor forward(const torch::Tensor& x);
  // The map before pooling: [B, out_features, S', S', S'] (S' = 8 for the paper preset at 128³).
  torch::Tensor feature_map(const torch::Tensor& x);
  // The stem's map (conv1 → BN → ReLU, before the max pool): [B, stem_channels, ⌈S/2⌉³].
  torch::Tensor stem(const torch::Tensor& x);
  // One pass for both uses: {stem(x), forward(x)}.
  std::pair<torch::Tensor, torch::Tensor> forward_with_stem(const torch::Tensor& x);

  int64_t out_features() const { return resnet3d_out_features(options_); }
  const ResNet3dOptions& options() const { return options_; }

 private:
  std::pair<torch::Tensor, torch::Tensor> stem_and_map(const torch::Tensor& x);  // {stem, map}

  ResNet3dOptions options_;
  torch::nn::Conv3d conv1{nullptr};
  torch::nn::BatchNorm3d bn1{nullptr};
  std::vector<torch::nn::Sequential> layers_;
};
TORCH_MODULE(ResNet3d);

}  // namespace neraf::acoustic
