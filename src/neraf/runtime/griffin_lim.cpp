#include "neraf/runtime/griffin_lim.h"

#include <algorithm>
#include <cstring>
#include <mutex>
#include <new>
#include <random>

#if defined(__AVX512F__) || defined(__AVX2__)
#include <immintrin.h>
#endif

#include "neraf/runtime/fftw_planner.h"
#include "neraf/runtime/stft_window.h"

namespace neraf::rt {
namespace {

// Multiple of 16 floats (64 bytes): rows at such offsets keep the buffer's FFTW alignment.
size_t aligned_stride(size_t n) { return (n + 15) / 16 * 16; }

int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Torch's reflect padding (no edge repeat; repeated for pads longer than the signal).
int64_t reflect_index(int64_t j, int64_t len) {
  if (len <= 1) return 0;
  const int64_t period = 2 * (len - 1);
  j = j < 0 ? -j : j;
  j %= period;
  return j < len ? j : period - j;
}

// The momentum update of one frame, in place (a copy of dsp/griffin_lim.cpp's, so both compile
// to the same arithmetic): r = b, a = r − m·prev, prev = r, b = S·a/(|a| + 1e-16).
void momentum_update(float* b, float* prev, const float* mag, int n_freq, float m) {
  int f = 0;
#if defined(__AVX512F__)
  const __m512 vm = _mm512_set1_ps(m);
  const __m512 eps = _mm512_set1_ps(1e-16f);
  const __m512i dup = _mm512_set_epi32(7, 7, 6, 6, 5, 5, 4, 4, 3, 3, 2, 2, 1, 1, 0, 0);
  for (; f + 8 <= n_freq; f += 8) {
    const __m512 r = _mm512_loadu_ps(b + 2 * f);
    const __m512 p = _mm512_loadu_ps(prev + 2 * f);
    const __m512 a = _mm512_sub_ps(r, _mm512_mul_ps(vm, p));
    const __m512 sq = _mm512_mul_ps(a, a);
    const __m512 norm2 =
        _mm512_add_ps(sq, _mm512_mask_permute_ps(sq, 0xFFFF, sq, 0xB1));  // re²+im²
    const __m512 den = _mm512_add_ps(_mm512_mask_sqrt_ps(norm2, 0xFFFF, norm2), eps);
    const __m512 m8 = _mm512_maskz_loadu_ps(0xFF, mag + f);
    const __m512 s = _mm512_mask_permutexvar_ps(m8, 0xFFFF, dup, m8);  // each magnitude twice
    _mm512_storeu_ps(prev + 2 * f, r);
    _mm512_storeu_ps(b + 2 * f, _mm512_mul_ps(a, _mm512_div_ps(s, den)));
  }
#elif defined(__AVX2__)
  const __m256 vm = _mm256_set1_ps(m);
  const __m256 eps = _mm256_set1_ps(1e-16f);
  const __m256i dup = _mm256_set_epi32(3, 3, 2, 2, 1, 1, 0, 0);
  for (; f + 4 <= n_freq; f += 4) {
    const __m256 r = _mm256_loadu_ps(b + 2 * f);
    const __m256 p = _mm256_loadu_ps(prev + 2 * f);
    const __m256 a = _mm256_sub_ps(r, _mm256_mul_ps(vm, p));
    const __m256 sq = _mm256_mul_ps(a, a);
    const __m256 norm2 = _mm256_add_ps(sq, _mm256_permute_ps(sq, 0xB1));
    const __m256 den = _mm256_add_ps(_mm256_sqrt_ps(norm2), eps);
    const __m128 m4 = _mm_loadu_ps(mag + f);
    const __m256 s = _mm256_permutevar8x32_ps(_mm256_set_m128(m4, m4), dup);
    _mm256_storeu_ps(prev + 2 * f, r);
    _mm256_storeu_ps(b + 2 * f, _mm256_mul_ps(a, _mm256_div_ps(s, den)));
  }
#endif
  for (; f < n_freq; ++f) {
    const float rr = b[2 * f], ri = b[2 * f + 1];
    const float ar = rr - m * prev[2 * f], ai = ri - m * prev[2 * f + 1];
    const float scale = mag[f] / (std::sqrt(ar * ar + ai * ai) + 1e-16f);
    prev[2 * f] = rr;
    prev[2 * f + 1] = ri;
    b[2 * f] = ar * scale;
    b[2 * f + 1] = ai * scale;
  }
}

}  // namespace

FftwFloats alloc_fftw_floats(size_t n) {
  float* p = fftwf_alloc_real(n == 0 ? 1 : n);
  if (!p) throw std::bad_alloc();
  std::memset(p, 0, (n == 0 ? 1 : n) * sizeof(float));
  return FftwFloats(p);
}

GriffinLim::GriffinLim(int n_fft, int win_length, int hop_length, int n_frames)
    : n_fft_(n_fft), n_freq_(n_fft / 2 + 1), hop_(hop_length), n_frames_(n_frames) {
  sb_ = (n_fft - win_length) / 2;
  se_ = sb_ + win_length;
  window_ = padded_hann_window(n_fft, win_length);
  spec_stride_ = aligned_stride(2 * size_t(n_freq_));
  frame_stride_ = aligned_stride(size_t(n_fft_));

  // dsp::griffin_lim without a `length`: the iterations and the output use torch.istft's default.
  const int64_t off = n_fft_ / 2;
  const int64_t expected = n_fft_ + int64_t(hop_) * (n_frames_ - 1);  // the frames' reach
  length_ = expected - 2 * off;
  c0_ = off;
  c1_ = std::min(off + length_, expected);
  sig_len_ = length_ + 2 * off;
  n_blocks_ = (c1_ + hop_ - 1) / hop_ - c0_ / hop_;
  block_first_ = c0_ / hop_;

  // 1/(n_fft·Σ_t w²[c − t·hop]) over [c0, c1), summed in double (StftEngine::inverse_envelope).
  std::vector<double> env(size_t(c1_ - c0_), 0.0);
  for (int t = 0; t < n_frames_; ++t) {
    const int64_t base = int64_t(t) * hop_;
    const int64_t a = std::max(c0_, base + sb_), b = std::min(c1_, base + se_);
    for (int64_t c = a; c < b; ++c) {
      const double w = window_[c - base];
      env[c - c0_] += w * w;
    }
  }
  inv_env_.resize(env.size());
  for (size_t i = 0; i < env.size(); ++i)
    inv_env_[i] = env[i] > 1e-11 ? static_cast<float>(1.0 / (double(n_fft_) * env[i])) : 0.0f;

  // Planned on arrays aligned like every buffer they will run on (alloc_fftw_floats, rows at
  // multiples of 16 floats). FFTW_ESTIMATE picks the algorithm from the size alone, as dsp's
  // plan cache does: the same transforms, the same rounding.
  FftwFloats a = alloc_fftw_floats(spec_stride_), b = alloc_fftw_floats(spec_stride_);
  std::lock_guard<std::mutex> lock(fftw_planner_mutex());
  r2c_ = fftwf_plan_dft_r2c_1d(n_fft_, a.get(), reinterpret_cast<fftwf_complex*>(b.get()),
                               FFTW_ESTIMATE);
  c2r_ = fftwf_plan_dft_c2r_1d(n_fft_, reinterpret_cast<fftwf_complex*>(a.get()), b.get(),
                               FFTW_ESTIMATE);
  if (!r2c_ || !c2r_) {  // FFTW only fails to plan when out of memory
    if (r2c_) fftwf_destroy_plan(r2c_);
    if (c2r_) fftwf_destroy_plan(c2r_);
    throw std::bad_alloc();
  }
}

GriffinLim::~GriffinLim() {
  std::lock_guard<std::mutex> lock(fftw_planner_mutex());
  fftwf_destroy_plan(r2c_);
  fftwf_destroy_plan(c2r_);
}

GriffinLimBuffers GriffinLim::make_buffers() const {
  GriffinLimBuffers b;
  b.spec = alloc_fftw_floats(size_t(n_frames_) * spec_stride_);
  b.frames = alloc_fftw_floats(size_t(n_frames_) * frame_stride_);
  b.scratch = alloc_fftw_floats(size_t(n_fft_));
  b.prev.assign(size_t(n_frames_) * 2 * n_freq_, 0.0f);
  b.mag.assign(size_t(n_frames_) * n_freq_, 0.0f);
  b.sig.assign(size_t(sig_len_), 0.0f);
  b.edge.assign(size_t(n_fft_), 0.0f);
  return b;
}

void GriffinLim::random_phases(uint64_t seed, int channels, float* out) const {
  std::mt19937 gen(static_cast<uint32_t>(seed & 0xffffffffu));
  const int F = n_freq_, T = n_frames_;
  for (int c = 0; c < channels; ++c)
    for (int f = 0; f < F; ++f)
      for (int t = 0; t < T; ++t) {
        float* p = out + ((size_t(c) * T + t) * F + f) * 2;
        p[0] = static_cast<float>(gen() & 0xFFFFFFu) * (1.0f / 16777216.0f);
        p[1] = static_cast<float>(gen() & 0xFFFFFFu) * (1.0f / 16777216.0f);
      }
}

void GriffinLim::forward_frame(const float* support, float* scratch, float* spec) const {
  const float* w = window_.data() + sb_;
  float* dst = scratch + sb_;
  for (int j = 0; j < se_ - sb_; ++j) dst[j] = support[j] * w[j];
  fftwf_execute_dft_r2c(r2c_, scratch, reinterpret_cast<fftwf_complex*>(spec));
}

// out[c − c0] = inv_env · Σ_t w[c − t·hop]·frames[t][c − t·hop] for c in [c0, c1) ∩ the block
// (StftEngine::overlap_add: the sum in increasing t).
void GriffinLim::overlap_add(const float* frames, int64_t block_begin, int64_t block_end,
                             float* out) const {
  const int64_t lo = std::max(c0_, block_begin), hi = std::min(c1_, block_end);
  if (lo >= hi) return;
  float* o = out - c0_;  // o[c] for OLA coordinate c
  std::fill(o + lo, o + hi, 0.0f);
  const int64_t t_first = std::max<int64_t>(0, floor_div(lo - se_, hop_) + 1);
  const int64_t t_last = std::min<int64_t>(n_frames_ - 1, floor_div(hi - sb_ - 1, hop_));
  const float* w = window_.data();
  for (int64_t t = t_first; t <= t_last; ++t) {
    const int64_t base = t * hop_;
    const int64_t a = std::max(lo, base + sb_), b = std::min(hi, base + se_);
    const float* f = frames + size_t(t) * frame_stride_ - base;
    const float* wb = w - base;
    for (int64_t c = a; c < b; ++c) o[c] += f[c] * wb[c];
  }
  const float* ie = inv_env_.data() - c0_;
  for (int64_t c = lo; c < hi; ++c) o[c] *= ie[c];
}

void GriffinLim::run(const float* mag, const float* phases, int n_iter, GriffinLimBuffers& b,
                     float* out, int64_t out_len) const {
  const int F = n_freq_, T = n_frames_;
  const int64_t off = n_fft_ / 2;
  const float m = static_cast<float>(double(kMomentum) / (1.0 + double(kMomentum)));

  // S·a with the initial phases; tprev = 0.
  std::fill(b.prev.begin(), b.prev.end(), 0.0f);
  for (int t = 0; t < T; ++t) {
    float* s = b.spec.get() + size_t(t) * spec_stride_;
    float* mt = b.mag.data() + size_t(t) * F;
    const float* ph = phases + size_t(t) * 2 * F;
    for (int f = 0; f < F; ++f) {
      const float v = mag[size_t(f) * T + t];
      mt[f] = v;
      s[2 * f] = v * ph[2 * f];
      s[2 * f + 1] = v * ph[2 * f + 1];
    }
  }
  auto inverse = [&](int t) {
    fftwf_execute_dft_c2r(c2r_,
                          reinterpret_cast<fftwf_complex*>(b.spec.get() + size_t(t) * spec_stride_),
                          b.frames.get() + size_t(t) * frame_stride_);
  };
  // x = istft(S·a): overlap-add the inverse-transformed frames, block by block.
  auto istft = [&] {
    for (int64_t i = 0; i < n_blocks_; ++i) {
      const int64_t k = block_first_ + i;
      overlap_add(b.frames.get(), k * hop_, (k + 1) * hop_, b.sig.data() + c0_);
    }
  };
  for (int t = 0; t < T; ++t) inverse(t);
  for (int it = 0; it < n_iter; ++it) {
    istft();
    // r = stft(x) (reflect-padded), a = r − m·prev, prev = r, S·a and its inverse FFT, frame by
    // frame while it is in cache.
    const float* x = b.sig.data() + off;
    for (int t = 0; t < T; ++t) {
      float* s = b.spec.get() + size_t(t) * spec_stride_;
      const int64_t start = int64_t(t) * hop_;
      if (start + sb_ >= off && start + se_ <= off + length_) {
        forward_frame(b.sig.data() + start + sb_, b.scratch.get(), s);
      } else {
        for (int j = 0; j < se_ - sb_; ++j) {
          const int64_t k = start + sb_ + j - off;  // index into x, maybe outside
          b.edge[j] = (k >= 0 && k < length_) ? x[k] : x[reflect_index(k, length_)];
        }
        forward_frame(b.edge.data(), b.scratch.get(), s);
      }
      momentum_update(s, b.prev.data() + size_t(t) * 2 * F, b.mag.data() + size_t(t) * F, F, m);
      inverse(t);
    }
  }
  istft();  // the final istft(S·a)

  const int64_t copy = std::max<int64_t>(0, std::min(out_len, c1_ - c0_));
  std::copy(b.sig.begin() + c0_, b.sig.begin() + c0_ + copy, out);
  std::fill(out + copy, out + out_len, 0.0f);
}

}  // namespace neraf::rt
