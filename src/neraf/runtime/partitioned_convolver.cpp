#include "neraf/runtime/partitioned_convolver.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <new>

#if defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "neraf/runtime/fftw_planner.h"

namespace neraf::rt {

AlignedFloats alloc_aligned(size_t n) {
  // aligned_alloc wants a size that is a multiple of the alignment.
  const size_t bytes = (std::max<size_t>(n, 1) * sizeof(float) + 63) / 64 * 64;
  if (bytes / sizeof(float) < n) throw std::bad_alloc();  // overflow
  float* p = static_cast<float*>(std::aligned_alloc(64, bytes));
  if (!p) throw std::bad_alloc();
  std::memset(p, 0, bytes);  // also commits the pages now, not on the audio thread later
  return AlignedFloats(p);
}

namespace {

constexpr double kPi = 3.14159265358979323846;

size_t round_up16(size_t n) { return (n + 15) / 16 * 16; }

// Flushes denormals to zero for the scope (FTZ and DAZ on x86), restoring the caller's mode
// after: a decaying RIR tail times a fading input produces denormals, which cost ~100 cycles
// each and would make a quiet block many times slower than a loud one.
class DenormalsOff {
 public:
#if defined(__SSE__)
  DenormalsOff() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | 0x8040u); }
  ~DenormalsOff() { _mm_setcsr(saved_); }

 private:
  unsigned saved_;
#endif
};

// acc += x * h over n bins, split complex: each pointer is a real row of n floats followed (at
// +n) by the imaginary row. 64-byte aligned, n a multiple of 16, no aliasing: one FMA stream
// that -O3 vectorises without a remainder loop.
inline void multiply_accumulate(float* __restrict acc, const float* __restrict x,
                                const float* __restrict h, size_t n) {
  acc = static_cast<float*>(__builtin_assume_aligned(acc, 64));
  x = static_cast<const float*>(__builtin_assume_aligned(x, 64));
  h = static_cast<const float*>(__builtin_assume_aligned(h, 64));
  float* __restrict ar = acc;
  float* __restrict ai = acc + n;
  const float* __restrict xr = x;
  const float* __restrict xi = x + n;
  const float* __restrict hr = h;
  const float* __restrict hi = h + n;
  if (n % 16 != 0) __builtin_unreachable();  // no remainder loop
  for (size_t k = 0; k < n; ++k) {
    float r = ar[k], i = ai[k];  // written so that each product contracts into an FMA
    r += xr[k] * hr[k];
    r -= xi[k] * hi[k];
    i += xr[k] * hi[k];
    i += xi[k] * hr[k];
    ar[k] = r;
    ai[k] = i;
  }
}

// The same for two partitions at once: acc += x0 * h0 + x1 * h1. Halves the loads and stores of
// the accumulator, which otherwise make the loop bound by memory traffic rather than by FMAs.
inline void multiply_accumulate2(float* __restrict acc, const float* __restrict x0,
                                 const float* __restrict h0, const float* __restrict x1,
                                 const float* __restrict h1, size_t n) {
  acc = static_cast<float*>(__builtin_assume_aligned(acc, 64));
  x0 = static_cast<const float*>(__builtin_assume_aligned(x0, 64));
  h0 = static_cast<const float*>(__builtin_assume_aligned(h0, 64));
  x1 = static_cast<const float*>(__builtin_assume_aligned(x1, 64));
  h1 = static_cast<const float*>(__builtin_assume_aligned(h1, 64));
  float* __restrict ar = acc;
  float* __restrict ai = acc + n;
  if (n % 16 != 0) __builtin_unreachable();
  for (size_t k = 0; k < n; ++k) {
    const float xr0 = x0[k], xi0 = x0[n + k], hr0 = h0[k], hi0 = h0[n + k];
    const float xr1 = x1[k], xi1 = x1[n + k], hr1 = h1[k], hi1 = h1[n + k];
    // One running sum each, so that every product contracts into one FMA (4 per output).
    float r = ar[k], i = ai[k];
    r += xr0 * hr0;
    r -= xi0 * hi0;
    r += xr1 * hr1;
    r -= xi1 * hi1;
    i += xr0 * hi0;
    i += xi0 * hr0;
    i += xr1 * hi1;
    i += xi1 * hr1;
    ar[k] = r;
    ai[k] = i;
  }
}

}  // namespace

size_t PartitionedConvolver::slot_bytes(int channels, int block_size, size_t max_rir_length) {
  const size_t b = size_t(block_size);
  const size_t parts = (max_rir_length + b - 1) / b;
  return SlotExchange::kSlots * parts * size_t(channels) * 2 * round_up16(b + 1) * sizeof(float);
}

PartitionedConvolver::PartitionedConvolver(int channels, int block_size, size_t max_rir_length)
    : channels_(channels),
      block_(block_size),
      max_len_(max_rir_length),
      n_fft_(2 * size_t(block_size)),
      n_bins_(size_t(block_size) + 1),
      kp_(round_up16(n_bins_)),
      row_(2 * kp_),
      p_max_((max_rir_length + size_t(block_size) - 1) / size_t(block_size)) {
  const size_t b = size_t(block_);
  time_ = alloc_aligned(n_fft_);
  spec_ = alloc_aligned(2 * n_bins_);
  fdl_ = alloc_aligned(p_max_ * row_);
  acc_ = alloc_aligned(size_t(channels_) * row_);
  y_ = alloc_aligned(n_fft_);
  fade_ = alloc_aligned(b);
  prep_time_ = alloc_aligned(n_fft_);
  prep_spec_ = alloc_aligned(2 * n_bins_);
  for (Slot& s : slots_) s.spectra = alloc_aligned(p_max_ * size_t(channels_) * row_);

  // w[n] = (1 - cos(pi (n + 1) / B)) / 2: the last sample of the block before the change has
  // weight 0 (w[-1]), the block's last sample weight 1; smooth (zero slope) at both ends.
  for (size_t n = 0; n < b; ++n)
    fade_[n] = static_cast<float>(0.5 - 0.5 * std::cos(kPi * double(n + 1) / double(b)));

  {
    // FFTW_MEASURE times a few algorithms on these very arrays (overwriting them, hence before
    // they hold data): ~2x faster transforms than FFTW_ESTIMATE's guess at some sizes, paid once
    // here. process() and set_rir() execute the plans on other arrays of the same alignment
    // through the thread-safe new-array interface.
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    const int n = static_cast<int>(n_fft_);
    r2c_ = fftwf_plan_dft_r2c_1d(n, time_.get(), reinterpret_cast<fftwf_complex*>(spec_.get()),
                                 FFTW_MEASURE);
    c2r_ = fftwf_plan_dft_c2r_1d(n, reinterpret_cast<fftwf_complex*>(spec_.get()), y_.get(),
                                 FFTW_MEASURE);
    if (!r2c_ || !c2r_) {  // FFTW only fails to plan when out of memory
      if (r2c_) fftwf_destroy_plan(r2c_);
      if (c2r_) fftwf_destroy_plan(c2r_);
      throw std::bad_alloc();  // (no destructor runs for a constructor that throws)
    }
  }
  std::memset(time_.get(), 0, n_fft_ * sizeof(float));
  std::memset(spec_.get(), 0, 2 * n_bins_ * sizeof(float));
  std::memset(y_.get(), 0, n_fft_ * sizeof(float));
}

PartitionedConvolver::~PartitionedConvolver() {
  std::lock_guard<std::mutex> lock(fftw_planner_mutex());
  if (r2c_) fftwf_destroy_plan(r2c_);
  if (c2r_) fftwf_destroy_plan(c2r_);
  r2c_ = c2r_ = nullptr;
}

void PartitionedConvolver::set_rir(const float* rir, size_t length, size_t stride) {
  const size_t b = size_t(block_);
  length = std::min(length, max_len_);
  Slot& slot = slots_[exchange_.writable()];
  slot.n_parts = (length + b - 1) / b;
  // The 1 / 2B of the unnormalised inverse FFT, folded into the partitions once.
  const float scale = 1.0f / static_cast<float>(n_fft_);
  float* t = prep_time_.get();
  const float* s = prep_spec_.get();
  for (size_t p = 0; p < slot.n_parts; ++p) {
    const size_t count = std::min(b, length - p * b);
    for (int c = 0; c < channels_; ++c) {
      std::memcpy(t, rir + size_t(c) * stride + p * b, count * sizeof(float));
      std::memset(t + count, 0, (n_fft_ - count) * sizeof(float));
      fftwf_execute_dft_r2c(r2c_, t, reinterpret_cast<fftwf_complex*>(prep_spec_.get()));
      float* re = slot.spectra.get() + (p * size_t(channels_) + size_t(c)) * row_;
      float* im = re + kp_;
      for (size_t k = 0; k < n_bins_; ++k) {
        re[k] = s[2 * k] * scale;
        im[k] = s[2 * k + 1] * scale;
      }
      // Bins n_bins_ .. kp_ stay zero from the allocation: never written.
    }
  }
  exchange_.publish();
}

void PartitionedConvolver::accumulate(const Slot& slot) {
  const size_t c_count = size_t(channels_);
  std::memset(acc_.get(), 0, c_count * row_ * sizeof(float));
  // FDL index of partition p: the spectrum of p blocks ago.
  auto fdl_row = [&](size_t p) {
    const size_t i = fdl_head_ >= p ? fdl_head_ - p : fdl_head_ + p_max_ - p;
    return fdl_.get() + i * row_;
  };
  const float* h = slot.spectra.get();
  size_t p = 0;
  // Partitions in pairs (the FDL row of a pair is read once per channel from L1).
  for (; p + 1 < slot.n_parts; p += 2) {
    const float* x0 = fdl_row(p);
    const float* x1 = fdl_row(p + 1);
    const float* h0 = h + p * c_count * row_;
    const float* h1 = h0 + c_count * row_;
    for (size_t c = 0; c < c_count; ++c)
      multiply_accumulate2(acc_.get() + c * row_, x0, h0 + c * row_, x1, h1 + c * row_, kp_);
  }
  if (p < slot.n_parts) {
    const float* x = fdl_row(p);
    const float* h0 = h + p * c_count * row_;
    for (size_t c = 0; c < c_count; ++c)
      multiply_accumulate(acc_.get() + c * row_, x, h0 + c * row_, kp_);
  }
}

void PartitionedConvolver::render(const Slot& slot, float* out, const float* fade) {
  const size_t b = size_t(block_);
  if (slot.n_parts == 0) {  // silence
    for (int c = 0; c < channels_; ++c) {
      float* o = out + size_t(c) * b;
      if (fade)
        for (size_t n = 0; n < b; ++n) o[n] -= fade[n] * o[n];
      else
        std::memset(o, 0, b * sizeof(float));
    }
    return;
  }
  accumulate(slot);
  float* s = spec_.get();
  const float* y = y_.get() + b;  // the valid half of the circular convolution
  for (int c = 0; c < channels_; ++c) {
    const float* re = acc_.get() + size_t(c) * row_;
    const float* im = re + kp_;
    for (size_t k = 0; k < n_bins_; ++k) {
      s[2 * k] = re[k];
      s[2 * k + 1] = im[k];
    }
    fftwf_execute_dft_c2r(c2r_, reinterpret_cast<fftwf_complex*>(s), y_.get());
    float* o = out + size_t(c) * b;
    if (fade)
      for (size_t n = 0; n < b; ++n) o[n] += fade[n] * (y[n] - o[n]);
    else
      std::memcpy(o, y, b * sizeof(float));
  }
}

void PartitionedConvolver::process(const float* in, float* out) {
  DenormalsOff denormals_off;
  const size_t b = size_t(block_);
  const bool changed = exchange_.take_newest();
  const bool crossfade = changed && started_;
  started_ = true;

  // This block's input spectrum (of the last 2B samples) becomes the FDL's newest row. `in` is
  // consumed before `out` is written, so the two may overlap.
  float* t = time_.get();
  std::memcpy(t + b, in, b * sizeof(float));
  fftwf_execute_dft_r2c(r2c_, t, reinterpret_cast<fftwf_complex*>(spec_.get()));
  std::memcpy(t, t + b, b * sizeof(float));  // the previous block of the next call
  fdl_head_ = fdl_head_ + 1 == p_max_ ? 0 : fdl_head_ + 1;
  float* re = fdl_.get() + fdl_head_ * row_;
  float* im = re + kp_;
  const float* s = spec_.get();
  for (size_t k = 0; k < n_bins_; ++k) {
    re[k] = s[2 * k];
    im[k] = s[2 * k + 1];
  }

  const Slot& now = slots_[exchange_.current()];
  if (crossfade) {
    render(slots_[exchange_.previous()], out, nullptr);  // the old RIR's block
    render(now, out, fade_.get());                        // faded into the new one's
  } else {
    render(now, out, nullptr);
  }
}

}  // namespace neraf::rt
