#pragma once
// NAcF: the acoustic field MLP (neraf-reference.md §1.2-1.3). One query = (scene feature, time
// frame, mic position, source position, orientation) → log(|STFT| + 1e-3) of one time frame, per
// channel.
//
// Input layout (nacf_input): [grid_feature (G), time (21), mic (63), source (63), rot (16)], G =
// 1024 for preset paper → 1187 inputs. Without a grid (use_grid = false, an ablation) the reference
// order is [mic, source, time, rot] → 163 inputs.
//   time:      t/(max_len − 1) → NeRFEncoding(1 dim, 10 freqs, 0..8, include_input) → 21
//   positions: metres, normalised by the audio aabb into (0,1)³, zero vector when outside (the
//              reference's data-stage rule, normalize_to_box) → one shared NeRFEncoding(3 dims) →
//              63 each
//   rot:       ((cosθ+1)/2, 0.5, (sinθ+1)/2) → SH degree 4 with tcnn's input mapping 2v − 1 → 16
// Encodings of positions and rot run in float64 (the reference's dataset tensors are float64), time
// in float32 (an int tensor divided by an int in torch gives the default dtype); the concatenation
// is cast to float32, as the reference's `h.float()`.
//
// Trunk: Linear layers with LeakyReLU(0.1) after each; preset paper 1187→5096→2048→1024→1024→512
// (5096 is what the published code trains), preset cpu 5×512 (the paper's text). Heads: one
// Linear(W→F) per channel, out = 10·tanh(h), stacked [B, C, F]. PyTorch default Linear init.
//
// Relative geometry (ours; `cpu` preset on, `paper` off): the reference gives NAcF absolute
// positions only, so the direction and distance of the source as the listener hears it (what sets
// the arrival time, the direct level and the interaural differences) must be learned from a few
// dozen training positions, and held-out headings and off-grid positions generalise poorly
// (AV-NeRF's coordinate transformation makes the same point). With `relative_geometry` the input
// gains kRelativeGeometryDim features after the reference's 163 + G (encode_relative_geometry).
// They are computed from the positions in metres, before normalisation: a source outside the audio
// box (train mics ± 1 m; common for RAF loudspeakers) has a zero position encoding, as in the
// reference, but its true direction and distance.
//
// Precision: with `bf16` the trunk's matrix products run in bfloat16 (inputs and weights cast per
// call, fp32 master weights, fp32 gradients), activations between trunk layers stay bf16; the heads
// stay fp32 (0.6 % of the FLOPs) so the output is not rounded to bf16's 8-bit mantissa.
//
// Decay heads (ours, `--decay-heads`; off in every preset, docs/BENCHMARKS.md): each channel gains
// a second head, a slope per bin, and out = output_scale·tanh(level + τ·slope) with τ = t/(max_len
// − 1), the raw time input. A reverberant tail is a straight line in log-magnitude whose slope
// depends on where the query is; a LeakyReLU trunk given t and the position side by side can only
// piece that product together, the explicit τ·slope term states it.
#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/pimpl.h>
#include <torch/types.h>

#include <array>
#include <cstdint>
#include <vector>

#include "neraf/acoustic/local_geometry.h"

namespace neraf::acoustic {

constexpr int64_t kTimeEncodingDim = 21;
constexpr int64_t kPositionEncodingDim = 63;
constexpr int64_t kRotEncodingDim = 16;
// Everything but the grid feature: 21 + 63 + 63 + 16.
constexpr int64_t kPoseEncodingDim =
    kTimeEncodingDim + 2 * kPositionEncodingDim + kRotEncodingDim;  // 163
constexpr int64_t kRelativeGeometryDim = 22;

struct NacfOptions {
  int64_t grid_features = 1024;  // G; 0 = no grid (ablation: reference order mic, src, time, rot)
  std::vector<int64_t> trunk = {5096, 2048, 1024, 1024, 512};
  int64_t n_channels = 2;  // C: 2 SoundSpaces binaural, 1 RAF mono
  int64_t n_freq = 257;    // F: 257 SoundSpaces (n_fft 512), 513 RAF (n_fft 1024)
  double leaky_slope = 0.1;
  double output_scale = 10.0;          // out = output_scale·tanh(h)
  bool bf16 = false;                   // bf16 trunk matrix products (fp32 master weights)
  bool relative_geometry = false;      // append encode_relative_geometry (ours)
  double position_max_freq_exp = 8.0;  // mic/source NeRFEncoding (reference 8)
  // The audio aabb (m; the data's train mics ± 1 m, set by infer::audio_model_options): positions
  // are given in metres and normalised by it for the position encodings. The default unit box
  // makes metres and normalised coordinates the same.
  std::array<double, 3> box_min{0, 0, 0};
  std::array<double, 3> box_max{1, 1, 1};
  // Geometry per query (local_geometry.h; --grid-features local|both): how many features each
  // query appends after everything else (4·L of an L-channel volume; 0 = the published design),
  // and the map from the positions' metres into the radiance field's frame that reads them.
  int64_t local_features = 0;
  WorldToField world_to_field = kIdentityWorldToField;
  bool decay_heads = false;  // a slope head per channel beside each level head (above)

  std::array<double, 3> extent_m() const {
    return {box_max[0] - box_min[0], box_max[1] - box_min[1], box_max[2] - box_min[2]};
  }
  // Where the input holds τ = t/(max_len − 1), the time encoding's raw input (its last column):
  // after the grid feature, or after mic and source in the no-grid layout (nacf_input).
  int64_t time_input_column() const {
    return (grid_features > 0 ? grid_features : 2 * kPositionEncodingDim) + kTimeEncodingDim - 1;
  }
  int64_t in_features() const {
    return grid_features + kPoseEncodingDim + (relative_geometry ? kRelativeGeometryDim : 0) +
           local_features;
  }
};

NacfOptions nacf_paper_options(int64_t n_channels, int64_t n_freq, int64_t grid_features = 1024);
NacfOptions nacf_cpu_options(int64_t n_channels, int64_t n_freq, int64_t grid_features = 256);

// The three encodings, each [B, dim] float32.
torch::Tensor encode_time(const torch::Tensor& t, int64_t max_len);  // t: [B] int → [B, 21]
// [B, 3] → [B, 63]; max_freq_exp: the highest frequency exponent (reference 8: 2^8 cycles across
// the audio box).
torch::Tensor encode_position(const torch::Tensor& p_norm, double max_freq_exp = 8.0);
torch::Tensor encode_rot(const torch::Tensor& rot);  // [B, 3] → [B, 16]

// The reference's position normalisation (data::normalize_position's rule): p' = (p − min)/(max −
// min), the whole vector zero when any component lies outside the open interval (0, 1).
// p_m: [B, 3] metres → [B, 3] float64.
torch::Tensor normalize_to_box(const torch::Tensor& p_m, const std::array<double, 3>& box_min,
                               const std::array<double, 3>& box_max);

// The source as heard from the microphone (y up), from the positions in metres (d = src − mic,
// never the normalised positions, which are zero outside the box), the audio aabb size extent_m
// (for the relative distance) and the stored orientation (heading θ from cosθ = 2·rot0 − 1,
// sinθ = 2·rot2 − 1). With φ the azimuth of d in the x-z plane:
//   cos, sin of k(φ − θ) and of k(φ + θ), k = 1..3  (12: direction relative to the heading; both
//       senses of rotation because datasets disagree on it, and a constant offset is linear in
//       these; for a mono RAF set θ is the source's yaw, and φ + π its emission direction)
//   d_y/|d|, d_xz/|d|                                (2: elevation)
//   |d|/|extent|, ln(|d| / 1 m), sin, cos(2π·2^k·|d|/|extent|), k = 0..2  (8: distance)
// → [B, 22] float32 (computed in float64). |d| is clamped to ≥ 5 cm.
torch::Tensor encode_relative_geometry(const torch::Tensor& mic_m, const torch::Tensor& src_m,
                                       const torch::Tensor& rot,
                                       const std::array<double, 3>& extent_m);

// Builds the reference's NAcF input [B, G + 163] float32 from normalised positions.
//   grid_feature: [G] or [1, G] (broadcast to the batch) or [B, G]; undefined → no-grid layout.
//   t: [B] int64 frame index in [0, max_len); mic_norm, src_norm: [B, 3] normalised positions;
//   rot: [B, 3] stored orientation ((cosθ+1)/2, 0.5, (sinθ+1)/2). Any float dtype (float64
//   advised).
torch::Tensor nacf_input(const torch::Tensor& grid_feature, const torch::Tensor& t, int64_t max_len,
                         const torch::Tensor& mic_norm, const torch::Tensor& src_norm,
                         const torch::Tensor& rot, double position_max_freq_exp = 8.0);

// Every input a Nacf built with `options` expects, from positions in METRES (mic_m, src_m: [B, 3]):
// nacf_input of the positions normalised by options' box (normalize_to_box) with its position
// frequencies, then (options.relative_geometry) encode_relative_geometry of the metres, then
// (options.local_features > 0) `local`, [B, local_features] → [B, options.in_features()].
torch::Tensor nacf_input(const NacfOptions& options, const torch::Tensor& grid_feature,
                         const torch::Tensor& t, int64_t max_len, const torch::Tensor& mic_m,
                         const torch::Tensor& src_m, const torch::Tensor& rot,
                         const torch::Tensor& local = {});

class NacfImpl : public torch::nn::Module {
 public:
  explicit NacfImpl(NacfOptions options = {});

  // h: [B, in_features] float32 → [B, C, F] in (−output_scale, output_scale). Reads the
  // parameters only (no BatchNorm or dropout: the same in train and eval mode), so concurrent
  // calls are safe.
  torch::Tensor forward(const torch::Tensor& h) const;

  const NacfOptions& options() const { return options_; }
  int64_t trunk_parameter_count() const;
  int64_t head_parameter_count() const;

 private:
  NacfOptions options_;
  // Named like the reference (`soundfield.{0..4}`, `STFT_linear.{c}`) for checkpoint import.
  torch::nn::ModuleList soundfield{nullptr};
  torch::nn::ModuleList STFT_linear{nullptr};  // NOLINT(readability-identifier-naming)
  torch::nn::ModuleList decay_slope{nullptr};  // one Linear(W→F) per channel; decay_heads only
};
TORCH_MODULE(Nacf);

}  // namespace neraf::acoustic
