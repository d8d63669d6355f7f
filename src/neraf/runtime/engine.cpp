#include "neraf/runtime/engine.h"

#include <cblas.h>
#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <system_error>
#include <thread>
#include <utility>

#include "neraf/runtime/vector_math.h"

namespace neraf::rt {
namespace {

constexpr float kFloor = 1e-3f;        // the log-magnitude offset: log(|STFT| + 1e-3)
constexpr float kMaxMagnitude = 1e4f;  // acoustic::log_stft_to_magnitude's clip

// clip(e^x − 1e-3, 0, 1e4) (acoustic::log_stft_to_magnitude).
inline float magnitude_of(float x) {
  const float m = exp_approx(x) - kFloor;
  return m < 0.0f ? 0.0f : (m > kMaxMagnitude ? kMaxMagnitude : m);
}

// The threads BLAS uses for one product: OpenBLAS says (openblas_get_num_threads, looked up at
// run time: libblas.so.3 may be another BLAS); any other BLAS counts as one.
int blas_threads() {
  using Fn = int (*)();
  static const Fn get = reinterpret_cast<Fn>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  return get ? std::max(1, get()) : 1;
}

}  // namespace

Engine::Engine(const ModelData& m, const std::string& name, bool allow_bf16) {
  check_model_data(m, name);
  channels_ = m.channels;
  n_freq_ = m.n_freq;
  n_frames_ = m.max_len;
  rir_length_ = m.rir_length();
  leaky_slope_ = static_cast<float>(m.leaky_slope);
  output_scale_ = static_cast<float>(m.output_scale);
  box_min_ = m.box_min;
  box_max_ = m.box_max;
  extent_m_ = m.extent_m;
  relative_geometry_ = m.relative_geometry;
  position_freqs_ = encoding_frequencies(m.position_max_freq_exp);
  pose_dim_ = int(m.input_dim() - kTimeDim);

  // Layer 1 split into its time columns (folded into the table with the bias) and pose columns.
  const DenseLayer& l1 = m.trunk[0];
  const int h1 = int(l1.out), in1 = int(l1.in);
  first_width_ = h1;
  max_width_ = h1;
  time_table_.resize(size_t(n_frames_) * h1);
  w1_pose_.resize(size_t(h1) * pose_dim_);
  for (int h = 0; h < h1; ++h)
    std::copy_n(l1.weight.begin() + size_t(h) * in1 + kTimeDim, pose_dim_,
                w1_pose_.begin() + size_t(h) * pose_dim_);
  const std::array<float, kNumFrequencies> time_freqs = encoding_frequencies(8.0);
  float enc[kTimeDim];
  for (int t = 0; t < n_frames_; ++t) {
    encode_time(t, m.time_frames > 0 ? m.time_frames : n_frames_, time_freqs, enc);
    for (int h = 0; h < h1; ++h) {
      const float* w = l1.weight.data() + size_t(h) * in1;
      double acc = l1.bias[h];
      for (int k = 0; k < kTimeDim; ++k) acc += double(w[k]) * enc[k];
      time_table_[size_t(t) * h1 + h] = static_cast<float>(acc);
    }
  }
  if (allow_bf16 && m.bf16_storage && m.trunk.size() > 1) bf16_kernel_ = best_bf16_kernel();
  padded_frames_ = bf16_network() ? round_up(n_frames_, kTileRows) : n_frames_;
  for (size_t i = 1; i < m.trunk.size(); ++i) {
    const DenseLayer& d = m.trunk[i];
    if (bf16_network()) {
      bf16_layers_.emplace_back(d.weight.data(), int(d.out), int(d.in), bf16_kernel_);
      layers_.push_back({int(d.in), int(d.out), {}, d.bias});  // float32 weights not needed
      max_width_ = std::max(max_width_, bf16_layers_.back().out_padded());
    } else {
      layers_.push_back({int(d.in), int(d.out), d.weight, d.bias});
      max_width_ = std::max(max_width_, int(d.out));
    }
  }
  const int w = int(m.heads[0].in);
  if (!bf16_network()) head_weight_.resize(size_t(channels_) * n_freq_ * w);
  head_bias_.resize(size_t(channels_) * n_freq_);
  for (int c = 0; c < channels_; ++c) {
    if (bf16_network())
      bf16_heads_.emplace_back(m.heads[c].weight.data(), n_freq_, w, bf16_kernel_);
    else
      std::copy(m.heads[c].weight.begin(), m.heads[c].weight.end(),
                head_weight_.begin() + size_t(c) * n_freq_ * w);
    std::copy(m.heads[c].bias.begin(), m.heads[c].bias.end(),
              head_bias_.begin() + size_t(c) * n_freq_);
  }
  calibration_ = m.calibration;
  griffin_lim_ = std::make_unique<GriffinLim>(m.n_fft, m.win_length, m.hop_length, n_frames_);

  info_.format_version = format_version_of(m);  // the file's: 1 unless it needs time_frames
  info_.layout = m.layout;
  info_.sample_rate = m.sample_rate;
  info_.channels = m.channels;
  info_.n_freq = m.n_freq;
  info_.n_frames = m.max_len;
  info_.n_fft = m.n_fft;
  info_.win_length = m.win_length;
  info_.hop_length = m.hop_length;
  info_.rir_length = int(rir_length_);
  for (int k = 0; k < 3; ++k) {
    info_.box_min[k] = m.box_min[k];
    info_.box_max[k] = m.box_max[k];
  }
  std::snprintf(info_.neraf_version, sizeof info_.neraf_version, "%s", m.neraf_version.c_str());
}

void Engine::encode_pose(const neraf_pose& pose, float* out) const {
  const std::array<double, 3> mic = normalize_position(pose.mic, box_min_, box_max_);
  const std::array<double, 3> src = normalize_position(pose.source, box_min_, box_max_);
  const std::array<double, 3> rot = rot_from_yaw(pose.yaw_deg);
  double enc[2 * kPositionDim + kRotDim + kRelativeGeometryDim];  // in double, cast once
  encode_position(mic, position_freqs_, enc);
  encode_position(src, position_freqs_, enc + kPositionDim);
  encode_rot(rot, enc + 2 * kPositionDim);
  if (relative_geometry_)  // from the metres: a source outside the box keeps its direction
    encode_relative_geometry({pose.mic[0], pose.mic[1], pose.mic[2]},
                             {pose.source[0], pose.source[1], pose.source[2]}, rot, extent_m_,
                             enc + 2 * kPositionDim + kRotDim);
  for (int i = 0; i < pose_dim_; ++i) out[i] = static_cast<float>(enc[i]);
}

void Engine::log_stft(const neraf_pose& pose, Workspace& ws, float* out) const {
  query(pose, ws, out, nullptr);
}

void Engine::rir(const neraf_pose& pose, Workspace& ws, float* out) const {
  query(pose, ws, ws.log_stft_.data(), out);
}

void Engine::query(const neraf_pose& pose, Workspace& ws, float* log, float* wave) const {
  const int T = n_frames_, h1 = first_width_;
  // Our own column split of float32 products only when BLAS does not split them itself.
  const bool single_blas = blas_threads() == 1;
  encode_pose(pose, ws.pose_.data());
  cblas_sgemv(CblasRowMajor, CblasNoTrans, h1, pose_dim_, 1.0f, w1_pose_.data(), pose_dim_,
              ws.pose_.data(), 1, 0.0f, ws.u_.data(), 1);  // u = W1_pose·pose, [H1]

  const float slope = leaky_slope_;
  float* x = ws.act_a_.get();  // [T, width], row stride ld
  float* y = ws.act_b_.get();
  const float* u = ws.u_.data();
  for (int t = 0; t < T; ++t) {  // h1 = leaky(table[t] + u)
    const float* tab = time_table_.data() + size_t(t) * h1;
    float* xt = x + size_t(t) * h1;
    for (int h = 0; h < h1; ++h) {
      const float v = tab[h] + u[h];
      xt[h] = v > 0.0f ? v : v * slope;
    }
  }
  int width = h1;
  size_t ld = size_t(h1);
  for (size_t i = 0; i < layers_.size(); ++i) {
    const Layer& l = layers_[i];
    const size_t ld_y = bf16_network() ? size_t(bf16_layers_[i].out_padded()) : size_t(l.out);
    trunk_layer(i, ws, x, ld, y, ld_y, single_blas);
    for (int t = 0; t < T; ++t) {  // + bias, LeakyReLU
      float* yt = y + size_t(t) * ld_y;
      const float* b = l.bias.data();
      for (int h = 0; h < l.out; ++h) {
        const float v = yt[h] + b[h];
        yt[h] = v > 0.0f ? v : v * slope;
      }
    }
    std::swap(x, y);
    width = l.out;
    ld = ld_y;
  }

  // The channels: with helpers, each thread takes whole channels and their heads (always on the
  // bf16 path; on the float32 path unless BLAS threads the products itself: then one product for
  // all heads first). A log-STFT query with its heads done has too little left per channel to
  // repay waking a helper.
  int n_workers = std::min<int>(channels_, int(ws.helpers_.size()) + 1);
  const bool heads_per_channel = bf16_network() || (single_blas && n_workers > 1);
  if (bf16_network()) {  // the heads' input, packed once for every channel's product
    pack_activations(x, T, width, ld, padded_frames_, bf16_heads_[0].in_padded(),
                     ws.x_tiles_.data());
  } else if (!heads_per_channel) {
    // log[C·F, T] = W_heads[C·F, W]·xᵀ: rows (c, f), columns t, the [C, F, T] layout itself.
    cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasTrans, channels_ * n_freq_, T, width, 1.0f,
                head_weight_.data(), width, x, int(ld), 0.0f, log, T);
    if (!wave) n_workers = 1;
  }
  for (int w = 1; w < n_workers; ++w) {
    ws.channel_parts_[w - 1] = {this, &ws,  x, ld,        width,
                                log,  wave, w, n_workers, heads_per_channel};
    ws.helpers_[w - 1]->start(
        [](void* p) {
          const ChannelPart& part = *static_cast<const ChannelPart*>(p);
          part.engine->channels(part);
        },
        &ws.channel_parts_[w - 1]);
  }
  channels({this, &ws, x, ld, width, log, wave, 0, n_workers, heads_per_channel});
  for (int w = 1; w < n_workers; ++w) ws.helpers_[w - 1]->wait();
}

void Engine::trunk_layer(size_t i, Workspace& ws, const float* x, size_t ld_x, float* y,
                         size_t ld_y, bool split_float) const {
  const Layer& l = layers_[i];
  const int T = n_frames_;
  int n = l.out, granule = 16;
  if (bf16_network()) {
    const Bf16Matrix& a = bf16_layers_[i];
    pack_activations(x, T, l.in, ld_x, padded_frames_, a.in_padded(), ws.x_tiles_.data());
    n = a.out_padded();
    granule = 32;
  }
  // A helper takes half the columns of layers big enough to repay waking it (AMX computes
  // ~15× faster than float32, AVX512-BF16 ~2×, so their layers must be larger).
  const double macs = double(T) * l.in * l.out;
  const bool split = !ws.helpers_.empty() && n >= 2 * granule &&
                     (bf16_kernel_ == Bf16Kernel::amx      ? macs > 3e7
                      : bf16_kernel_ == Bf16Kernel::avx512 ? macs > 4e6
                                                           : split_float && macs > 2e6);
  const int mid = split ? (n / 2 + granule - 1) / granule * granule : n;
  if (split) {
    ws.layer_part_ = {this, &ws, i, x, ld_x, y, ld_y, mid, n};
    ws.helpers_[0]->start(
        [](void* p) {
          const LayerPart& part = *static_cast<const LayerPart*>(p);
          part.engine->layer_columns(part);
        },
        &ws.layer_part_);
  }
  layer_columns({this, &ws, i, x, ld_x, y, ld_y, 0, mid});
  if (split) ws.helpers_[0]->wait();
}

void Engine::layer_columns(const LayerPart& p) const {
  if (p.n_begin >= p.n_end) return;
  if (bf16_network()) {
    // y[padded T, columns] = bf16(x)·bf16(W)ᵀ (x packed by trunk_layer).
    bf16_layers_[p.layer].multiply(p.ws->x_tiles_.data(), padded_frames_, p.y, p.n_begin, p.n_end);
  } else {
    // y[T, columns] = x[T, in]·W[columns, in]ᵀ.
    const Layer& l = layers_[p.layer];
    cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasTrans, n_frames_, p.n_end - p.n_begin, l.in, 1.0f,
                p.x, int(p.ld_x), l.weight.data() + size_t(p.n_begin) * l.in, l.in, 0.0f,
                p.y + p.n_begin, int(p.ld_y));
  }
}

void Engine::channels(const ChannelPart& p) const {
  const int T = n_frames_, F = n_freq_;
  const size_t ft = size_t(F) * T;
  const size_t phase_floats = size_t(T) * griffin_lim_->phase_stride();
  const float scale = output_scale_;
  for (int c = p.worker; c < channels_; c += p.n_workers) {
    float* log = p.log + c * ft;  // [F, T]
    const float* bias = head_bias_.data() + size_t(c) * F;
    if (bf16_network()) {
      // y[padded T, padded F] = bf16(x)·bf16(W_c)ᵀ (x packed by query()), then output_scale·
      // tanh(. + bias) along each frame's row and the transpose into [F, T].
      const Bf16Matrix& head = bf16_heads_[c];
      const size_t ld_y = size_t(head.out_padded());
      float* y = p.ws->head_products_.data() + c * size_t(padded_frames_) * ld_y;
      head.multiply(p.ws->x_tiles_.data(), padded_frames_, y, 0, head.out_padded());
      for (int t = 0; t < T; ++t) {
        float* yt = y + size_t(t) * ld_y;
        for (int f = 0; f < F; ++f) yt[f] = tanh_approx(yt[f] + bias[f]) * scale;
      }
      for (int f = 0; f < F; ++f)
        for (int t = 0; t < T; ++t) log[size_t(f) * T + t] = y[size_t(t) * ld_y + f];
    } else {
      if (p.heads)
        cblas_sgemm(CblasRowMajor, CblasNoTrans, CblasTrans, F, T, p.width, 1.0f,
                    head_weight_.data() + c * size_t(F) * p.width, p.width, p.x, int(p.ld_x), 0.0f,
                    log, T);
      for (int f = 0; f < F; ++f) {  // output_scale·tanh(. + bias)
        float* o = log + size_t(f) * T;
        for (int t = 0; t < T; ++t) o[t] = tanh_approx(o[t] + bias[f]) * scale;
      }
    }
    if (!calibration_.empty()) {
      // log(clip(e^x − 1e-3, 0, 1e4)·g + 1e-3) (acoustic::apply_calibration).
      const float* g = calibration_.data() + c * ft;
      for (size_t i = 0; i < ft; ++i) log[i] = log_approx(magnitude_of(log[i]) * g[i] + kFloor);
    }
    if (p.wave) {
      for (size_t i = 0; i < ft; ++i) log[i] = magnitude_of(log[i]);  // in place: magnitudes
      griffin_lim_->run(log, p.ws->phases_.data() + c * phase_floats, p.ws->iterations_,
                        p.ws->gl_[c], p.wave + size_t(c) * rir_length_, rir_length_);
    }
  }
}

Workspace::Workspace(const Engine& engine, int threads) : engine_(engine) {
  const size_t rows = size_t(engine.padded_frames_);
  pose_.assign(size_t(engine.pose_dim_), 0.0f);
  u_.assign(size_t(engine.first_width_), 0.0f);
  act_a_ = alloc_fftw_floats(rows * engine.max_width_);
  act_b_ = alloc_fftw_floats(rows * engine.max_width_);
  size_t max_in = 0;
  for (const Bf16Matrix& a : engine.bf16_layers_) max_in = std::max(max_in, size_t(a.in_padded()));
  for (const Bf16Matrix& a : engine.bf16_heads_) max_in = std::max(max_in, size_t(a.in_padded()));
  x_tiles_.assign(rows * max_in, 0);
  if (!engine.bf16_heads_.empty())
    head_products_.assign(engine.bf16_heads_.size() * rows * engine.bf16_heads_[0].out_padded(),
                          0.0f);
  log_stft_.assign(engine.log_stft_size(), 0.0f);
  phases_.assign(size_t(engine.channels_) * engine.n_frames_ * engine.griffin_lim_->phase_stride(),
                 0.0f);
  for (int c = 0; c < engine.channels_; ++c) gl_.push_back(engine.griffin_lim_->make_buffers());
  set_griffin_lim(32, 0);
  set_threads(threads);
}

Workspace::~Workspace() = default;  // helpers join first (declared after the buffers they use)

void Workspace::set_griffin_lim(int iterations, uint64_t seed) {
  iterations_ = iterations;
  seed_ = seed;
  engine_.griffin_lim_->random_phases(seed, engine_.channels_, phases_.data());
}

void Workspace::set_threads(int threads) {
  int want = threads;
  if (want <= 0) {
    const int hw = int(std::thread::hardware_concurrency());
    want = std::max(1, std::min(engine_.channels_, hw));
  }
  want = std::min(want, engine_.channels_);  // more than one per channel would idle
  const size_t helpers = size_t(want - 1);
  while (helpers_.size() > helpers) helpers_.pop_back();
  while (helpers_.size() < helpers) {
    try {
      helpers_.push_back(std::make_unique<HelperThread>());
    } catch (const std::system_error&) {
      if (threads > 0) throw;  // asked for explicitly: report it
      break;                   // automatic: run with the threads there are
    }
  }
  channel_parts_.resize(helpers_.size());
}

}  // namespace neraf::rt
