#pragma once
// Inference of an exported acoustic field: pose → log-STFT [C, F, T] → waveform [C, rir_length],
// the numbers of the training code's render path (infer::AudioRun::predict_log_stft_batch, then
// Griffin-Lim) without LibTorch.
//
// One RIR is T frames of the same pose, so the first layer splits (inputs [time | pose]):
//   W1·[enc_time(t); pose] + b1 = table[t] + u,   table[t] = W1_time·enc_time(t) + b1 ([T, H1],
//   computed once at load, in double), u = W1_pose·pose (one gemv per RIR).
// Then h1 = leaky(table + u) ([T, H1]), each further trunk layer one sgemm over all T frames, the
// heads one sgemm that writes [C·F, T] = the output layout directly (the bf16 path: one product
// [T, F] per channel, transposed after the tanh), then
// output_scale·tanh, the energy calibration log(clip(e^x − 1e-3, 0, 1e4)·g + 1e-3) and, for
// waveforms, magnitudes clip(e^x − 1e-3, 0, 1e4) into Griffin-Lim (one channel per thread).
//
// Precision: float32, except for a model stored in bfloat16 (exported with --precision bf16,
// trained with a bf16 trunk) on a CPU with AMX-BF16 or AVX512-BF16: its trunk layers after the
// first and its heads then run in bfloat16 (bf16_gemm.h: inputs rounded to bf16 before each
// product, float32 accumulation; ~1e-2 from the float32 result in log-magnitude), unless the
// caller asks for float32. The training code's bf16 trunk rounds the same inputs: its
// activations between trunk layers, the heads' input included, are bf16, and a bf16 file's head
// weights are rounded already. Layer 1 (time table + pose gemv) runs in float32, as in training.
// Elsewhere a bf16 file runs its bf16-rounded weights in float32.
// The encodings run in double where the training code's do (positions, rot, relative geometry),
// the time encoding in float; exp, log and tanh are vectorised approximations (vector_math.h),
// so float32 results match the torch path to float rounding, not bit for bit.
//
// Threads: an Engine is immutable after construction and shared; a Workspace holds every buffer
// of a query (one per thread at a time) and its helper threads. With helpers, a query splits the
// columns of the large trunk layers between the caller and a helper, then each thread finishes
// whole channels (head, tanh, calibration, and for waveforms Griffin-Lim), so the channels run
// in parallel end to end. BLAS may use its own threads as well: when it reports more than one
// (OpenBLAS), the float32 products are left to it unsplit (two thread pools on the same cores
// only wait for each other). For steady latency, give BLAS one thread (OMP_NUM_THREADS=1 or
// OPENBLAS_NUM_THREADS=1) and let the workspace parallelise: OpenMP workers that spin after each
// product take the cores the Griffin-Lim helpers need.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "neraf/neraf_rt.h"
#include "neraf/runtime/bf16_gemm.h"
#include "neraf/runtime/griffin_lim.h"
#include "neraf/runtime/helper_thread.h"
#include "neraf/runtime/input_encoding.h"
#include "neraf/runtime/model_file.h"

namespace neraf::rt {

class Workspace;

class Engine {
 public:
  // Validates `m` (check_model_data: throws ModelFileError) and prepares the folded layers, the
  // time table and the Griffin-Lim plans. allow_bf16: run a bf16 model's trunk and heads in
  // bfloat16 where the CPU can (see above; best_bf16_kernel); false: float32 always. Throws
  // std::bad_alloc when out of memory.
  explicit Engine(const ModelData& m, const std::string& name = "model", bool allow_bf16 = true);

  // The kernel of the bfloat16 products (trunk and heads), or none when they run in float32.
  Bf16Kernel bf16_kernel() const { return bf16_kernel_; }
  // Whether trunk layers 2.. and the heads run in bfloat16 (else all in float32).
  bool bf16_network() const { return bf16_kernel_ != Bf16Kernel::none; }
  int channels() const { return channels_; }
  int n_freq() const { return n_freq_; }
  int n_frames() const { return n_frames_; }
  int64_t rir_length() const { return rir_length_; }
  size_t log_stft_size() const { return size_t(channels_) * n_freq_ * n_frames_; }  // C·F·T
  int pose_dim() const { return pose_dim_; }  // the input width without the time encoding
  const neraf_model_info& info() const { return info_; }
  const GriffinLim& griffin_lim() const { return *griffin_lim_; }

  // The canonical input of a pose without the time encoding: [mic (63), source (63), rot (16),
  // relative geometry (22 if any)], out[pose_dim()]. The pose is not validated here.
  void encode_pose(const neraf_pose& pose, float* out) const;

  // Calibrated log(|STFT| + 1e-3), out[C·F·T] as [C, F, T]. Allocates nothing.
  void log_stft(const neraf_pose& pose, Workspace& ws, float* out) const;
  // Griffin-Lim waveform, out[C·rir_length] planar. Allocates nothing.
  void rir(const neraf_pose& pose, Workspace& ws, float* out) const;

 private:
  friend class Workspace;
  struct Layer {
    int in = 0, out = 0;
    std::vector<float> weight;  // [out, in]
    std::vector<float> bias;    // [out]
  };
  struct LayerPart {  // columns [n_begin, n_end) of trunk layer `layer` for one thread
    const Engine* engine;
    Workspace* ws;
    size_t layer;
    const float* x;
    size_t ld_x;
    float* y;
    size_t ld_y;
    int n_begin, n_end;
  };
  struct ChannelPart {  // channels worker, worker + n_workers, ... for one thread
    const Engine* engine;
    Workspace* ws;
    const float* x;  // the trunk's output [T, width], row stride ld_x
    size_t ld_x;
    int width;
    float* log;   // [C, F, T]
    float* wave;  // [C, rir_length], or null for the log-STFT only
    int worker, n_workers;
    bool heads;  // compute the channel's head here (else the caller did all heads)
  };
  // The whole query: the trunk, then the channels; log: [C, F, T]; wave: [C, rir_length] or null.
  void query(const neraf_pose& pose, Workspace& ws, float* log, float* wave) const;
  // Trunk layer i (x → y, row strides ld_x, ld_y), its columns split with a helper when large.
  void trunk_layer(size_t i, Workspace& ws, const float* x, size_t ld_x, float* y, size_t ld_y,
                   bool split_float) const;
  void layer_columns(const LayerPart& p) const;
  void channels(const ChannelPart& p) const;

  neraf_model_info info_{};
  int channels_, n_freq_, n_frames_, pose_dim_, first_width_;
  int max_width_;      // the widest trunk layer (padded to 32 on the bf16 path)
  int padded_frames_;  // T rounded up to a tile's 16 rows (T on the float32 path)
  Bf16Kernel bf16_kernel_ = Bf16Kernel::none;
  int64_t rir_length_;
  float leaky_slope_, output_scale_;
  std::array<double, 3> box_min_, box_max_, extent_m_;
  bool relative_geometry_;
  std::array<float, kNumFrequencies> position_freqs_;
  std::vector<float> time_table_;        // [T, H1]: W1_time·enc_time(t) + b1
  std::vector<float> w1_pose_;           // [H1, pose_dim]: trunk[0]'s pose columns
  std::vector<Layer> layers_;            // trunk[1..] (weights float32; biases used by both paths)
  std::vector<Bf16Matrix> bf16_layers_;  // trunk[1..] packed (bf16 path), else empty
  std::vector<float> head_weight_;       // [C·F, W]: the heads stacked (float32 path)
  std::vector<Bf16Matrix> bf16_heads_;   // [C]: each channel's head packed (bf16 path)
  std::vector<float> head_bias_;         // [C·F]
  std::vector<float> calibration_;       // [C, F, T] or empty
  std::unique_ptr<GriffinLim> griffin_lim_;
};

class Workspace {
 public:
  // threads: how many threads a query uses (the caller plus threads − 1 helpers, see query());
  // 0 = automatic (one per channel, at most the hardware's).
  explicit Workspace(const Engine& engine, int threads = 0);
  ~Workspace();
  Workspace(const Workspace&) = delete;
  Workspace& operator=(const Workspace&) = delete;

  const Engine& engine() const { return engine_; }
  // Griffin-Lim iterations (default 32) and the seed of its initial phases (default 0).
  void set_griffin_lim(int iterations, uint64_t seed);
  void set_threads(int threads);  // as the constructor's; may start or stop helper threads
  int threads() const { return int(helpers_.size()) + 1; }

 private:
  friend class Engine;

  const Engine& engine_;
  std::vector<float> pose_;            // [pose_dim]
  std::vector<float> u_;               // [H1]: W1_pose·pose
  FftwFloats act_a_, act_b_;           // [padded T, max width]: trunk activations (ping-pong)
  std::vector<uint16_t> x_tiles_;      // the bf16 path's input tiles [padded T, padded width]
  std::vector<float> head_products_;   // the bf16 path's heads [C][padded T, padded F]
  std::vector<float> log_stft_;        // [C, F, T]: rir()'s log-STFT, then its magnitudes
  std::vector<float> phases_;          // [C][T][2F]: Griffin-Lim's initial phases for seed_
  std::vector<GriffinLimBuffers> gl_;  // [C]
  std::vector<std::unique_ptr<HelperThread>> helpers_;
  // The helpers' jobs, kept here so that queries allocate nothing.
  Engine::LayerPart layer_part_{};
  std::vector<Engine::ChannelPart> channel_parts_;  // [helpers]
  int iterations_ = 32;
  uint64_t seed_ = 0;
};

}  // namespace neraf::rt
