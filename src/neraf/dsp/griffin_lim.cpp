#include "neraf/dsp/griffin_lim.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>

#if defined(__AVX512F__) || defined(__AVX2__)
#include <immintrin.h>
#endif

#include "neraf/dsp/stft_engine.h"
#include "neraf/util/error.h"

namespace neraf::dsp {
namespace {

using detail::AlignedFloats;
using detail::StftEngine;

// torch's CPU generator is a 32-bit Mersenne twister seeded with the seed's low 32 bits, and a
// float32 uniform sample keeps the low 24 bits of one draw: (x & 0xFFFFFF) · 2^-24 (exact).
class TorchCpuRand {
 public:
  explicit TorchCpuRand(uint64_t seed) : gen_(static_cast<uint32_t>(seed & 0xffffffffu)) {}
  float next() { return static_cast<float>(gen_() & 0xFFFFFFu) * (1.0f / 16777216.0f); }

 private:
  std::mt19937 gen_;
};

// Per-channel state, frame-major so each frame's FFT and update touch one contiguous buffer.
struct Channel {
  AlignedFloats spec;       // [T][spec_stride]: r = stft(x), then S·a (complex)
  AlignedFloats frames;     // [T][frame_stride]: irfft(S·a) (real), read by the overlap-add
  std::vector<float> prev;  // [T][2F]: previous rebuilt spectrum (torch's tprev)
  std::vector<float> mag;   // [T][F]: target magnitude
  std::vector<float> sig;  // x = istft(...) at OLA coordinates [n/2, n/2 + len) (room for 0..len+n)
};

// The momentum update of one frame, in place: r = b (the rebuilt spectrum), a = r − m·prev,
// prev = r, b = S·a/(|a| + 1e-16). b, prev: n_freq interleaved complex values; mag: n_freq.
// Explicit SIMD because compilers keep sqrt scalar unless -fno-math-errno; sqrt and division
// are correctly rounded in every path, and a given frame always takes the same path, so results
// stay independent of the thread count.
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
    // (The full-mask _mask_ forms avoid GCC 12's false -Wmaybe-uninitialized on the plain ones.)
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

// Calls fn(i) for i in [0, n): shared by the current team's threads (an orphaned `omp for`, with
// its barrier) when `team`, else all on this thread.
template <typename Fn>
void team_for(bool team, int64_t n, const Fn& fn) {
  if (team) {
#pragma omp for schedule(static)
    for (int64_t i = 0; i < n; ++i) fn(i);
  } else {
    for (int64_t i = 0; i < n; ++i) fn(i);
  }
}

// Frames run in parallel only when the work pays for the threads.
constexpr int64_t kParallelSamples = 16384;

std::vector<std::vector<float>> run(const std::vector<const Matrix*>& mags, const StftParams& p,
                                    const GriffinLimOptions& o) {
  require(p.center,
          "griffin_lim: STFT parameters must be centred (torchaudio's griffinlim always "
          "uses center=True)");
  require(o.n_iter >= 0, "griffin_lim: n_iter must be >= 0, got " + std::to_string(o.n_iter));
  require(o.threads >= 0, "griffin_lim: threads must be >= 0 (0: automatic)");
  require(o.momentum >= 0.0f && o.momentum < 1.0f,
          "griffin_lim: momentum must be in [0, 1), got " + std::to_string(o.momentum));
  const StftEngine e(p);
  detail::validate_nola(e);

  const int n_ch = static_cast<int>(mags.size());
  const int F = p.n_freq();
  const int T = n_ch ? mags[0]->cols : 0;
  for (const Matrix* m : mags) {
    require(m->rows == F, "griffin_lim: the magnitude has " + std::to_string(m->rows) +
                              " frequency bins but n_fft " + std::to_string(p.n_fft) + " needs " +
                              std::to_string(F));
    require(m->cols == T, "griffin_lim: all channels must have the same number of frames");
    for (float v : m->data) {
      if (!std::isfinite(v))
        throw Error("griffin_lim: the magnitude contains NaN or infinite values");
    }
  }
  const int64_t default_len = e.default_length(T);
  const int64_t final_len = o.length ? int64_t(*o.length) : default_len;
  std::vector<std::vector<float>> out(n_ch,
                                      std::vector<float>(std::max<int64_t>(0, final_len), 0.0f));
  if (n_ch == 0 || T == 0) return out;

  const int n = p.n_fft;
  const int hop = p.hop_length;
  // The signal length inside the iterations: torchaudio passes `length` to every istft; its stft
  // then has 1 + length/hop frames, which must equal T (torch fails otherwise).
  const int64_t iter_len =
      (o.length && stft_num_frames(*o.length, p) == T) ? int64_t(*o.length) : default_len;
  const int64_t off = n / 2;
  const int64_t sig_len = iter_len + 2 * off;           // what the re-analysis frames read
  const int64_t expected = n + int64_t(hop) * (T - 1);  // what the frames' overlap-add reaches
  const int64_t c0 = off, c1 = std::min(off + iter_len, expected);
  const std::vector<float> inv_env = e.inverse_envelope(T, c0, c1);
  const float m = static_cast<float>(double(o.momentum) / (1.0 + double(o.momentum)));
  const size_t sstride = e.spec_stride();
  const size_t fstride = e.frame_stride();

  // Initial spectra S·a (serially, so the random stream is consumed in torch's order), then their
  // inverse FFTs below.
  TorchCpuRand rng(o.seed);
  std::vector<Channel> ch(n_ch);
  for (int c = 0; c < n_ch; ++c) {
    Channel& s = ch[c];
    s.spec = detail::alloc_floats(size_t(T) * sstride);
    s.frames = detail::alloc_floats(size_t(T) * fstride);
    s.prev.assign(size_t(T) * 2 * F, 0.0f);  // tprev starts at 0
    s.mag.resize(size_t(T) * F);
    s.sig.assign(sig_len, 0.0f);
    for (int f = 0; f < F; ++f) {
      for (int t = 0; t < T; ++t) {
        const float mag = (*mags[c])(f, t);
        s.mag[size_t(t) * F + f] = mag;
        const float re = o.rand_init ? rng.next() : 1.0f;
        const float im = o.rand_init ? rng.next() : 0.0f;
        float* b = s.spec.get() + size_t(t) * sstride;
        b[2 * f] = mag * re;
        b[2 * f + 1] = mag * im;
      }
    }
  }

  const int64_t n_blocks = (c1 + hop - 1) / hop - c0 / hop;  // output blocks of hop samples
  const int64_t block_first = c0 / hop;

  // Runs all iterations for channels [c_lo, c_hi). With `team` the loops are shared by the
  // threads of the enclosing parallel region (orphaned omp for: two barriers per iteration);
  // without, this thread does everything. Either way each value is computed by the same
  // arithmetic, so the mode never changes the result.
  auto iterate = [&](int c_lo, int c_hi, bool team, float* scratch, float* edge) {
    const int64_t nc = c_hi - c_lo;
    auto frame_at = [&](int64_t i) { return std::pair<Channel*, int>(&ch[c_lo + i / T], i % T); };
    // x = istft(S·a, length): overlap-add the inverse-transformed frames, divide by the envelope.
    auto overlap_add = [&](int64_t i) {
      Channel& s = ch[c_lo + i / n_blocks];
      const int64_t k = block_first + i % n_blocks;
      e.overlap_add(s.frames.get(), T, c0, c1, inv_env.data(), k * hop, (k + 1) * hop,
                    s.sig.data() + c0);
    };
    team_for(team, nc * T, [&](int64_t i) {
      auto [s, t] = frame_at(i);
      e.inverse_frame(s->spec.get() + size_t(t) * sstride, s->frames.get() + size_t(t) * fstride);
    });
    for (int it = 0; it < o.n_iter; ++it) {
      team_for(team, nc * n_blocks, overlap_add);
      // r = stft(x) with x centre-padded by reflection (center=True, pad_mode="reflect");
      // a = r − m·prev; a /= |a| + 1e-16; prev = r; then S·a and its inverse FFT for the next
      // istft, all while the frame is in cache. Frames that reach into the padding read the
      // reflected samples through `edge` (no separate padding pass: one barrier less).
      team_for(team, nc * T, [&](int64_t i) {
        auto [s, t] = frame_at(i);
        float* b = s->spec.get() + size_t(t) * sstride;
        const int64_t start = int64_t(t) * hop;
        if (start + e.support_begin() >= off && start + e.support_end() <= off + iter_len) {
          e.forward_frame(s->sig.data() + start + e.support_begin(), scratch, b);
        } else {
          const float* x = s->sig.data() + off;
          for (int j = 0; j < e.support_end() - e.support_begin(); ++j) {
            const int64_t k = start + e.support_begin() + j - off;  // index into x, maybe outside
            edge[j] = (k >= 0 && k < iter_len) ? x[k] : x[detail::reflect_index(k, iter_len)];
          }
          e.forward_frame(edge, scratch, b);
        }
        momentum_update(b, s->prev.data() + size_t(t) * 2 * F, s->mag.data() + size_t(t) * F, F, m);
        e.inverse_frame(b, s->frames.get() + size_t(t) * fstride);
      });
    }
    team_for(team, nc * n_blocks, overlap_add);  // the final istft(S·a, length)
  };

  // Per thread: the windowed frame fed to the r2c (zero outside the window support, which is
  // never written) and the reflected samples of frames that reach into the centre padding.
  int n_threads = o.threads > 0 ? o.threads : omp_get_max_threads();
  if (o.threads == 0 && (omp_in_parallel() || detail::cores_busy())) n_threads = 1;
  const bool parallel = n_threads > 1 && int64_t(n_ch) * T * n >= kParallelSamples;
  if (!parallel) {
    AlignedFloats scratch = detail::alloc_floats(n);
    std::vector<float> edge(n, 0.0f);
    iterate(0, n_ch, false, scratch.get(), edge.data());
  } else if (n_ch % n_threads == 0) {
    // Whole channels per thread (e.g. binaural on 2 cores): no barrier until the end.
#pragma omp parallel num_threads(n_threads)
    {
      AlignedFloats scratch = detail::alloc_floats(n);
      std::vector<float> edge(n, 0.0f);
#pragma omp for schedule(static)
      for (int c = 0; c < n_ch; ++c) iterate(c, c + 1, false, scratch.get(), edge.data());
    }
  } else {
#pragma omp parallel num_threads(n_threads)
    {
      AlignedFloats scratch = detail::alloc_floats(n);
      std::vector<float> edge(n, 0.0f);
      iterate(0, n_ch, true, scratch.get(), edge.data());
    }
  }

  // Positions past the frames' reach stay 0 (torch.istft zero-pads); a length torch could not use
  // inside the iterations pads or cuts the result here.
  for (int c = 0; c < n_ch; ++c) {
    const int64_t copy = std::min<int64_t>(final_len, c1 - c0);
    std::copy(ch[c].sig.begin() + c0, ch[c].sig.begin() + c0 + std::max<int64_t>(0, copy),
              out[c].begin());
  }
  return out;
}

}  // namespace

std::vector<float> griffin_lim(const Matrix& magnitude, const StftParams& p,
                               const GriffinLimOptions& options) {
  return std::move(run({&magnitude}, p, options)[0]);
}

std::vector<std::vector<float>> griffin_lim(const std::vector<Matrix>& magnitudes,
                                            const StftParams& p, const GriffinLimOptions& options) {
  std::vector<const Matrix*> ptrs;
  for (const Matrix& m : magnitudes) ptrs.push_back(&m);
  return run(ptrs, p, options);
}

}  // namespace neraf::dsp
