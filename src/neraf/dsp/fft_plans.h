#pragma once
// Internal to dsp (not part of the public API): single-precision FFTW plans shared by the STFT,
// Griffin-Lim and the FFT convolution, plus SIMD-aligned buffers to execute them on.
//
// Plans are executed with FFTW's new-array interface (fftwf_execute_dft_r2c/c2r), which is
// thread-safe; only plan *creation* is not, so plans are created under a mutex and cached for the
// life of the process (see fft_plans.cpp for why that cache is the one piece of process state).
#include <fftw3.h>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace neraf::dsp::detail {

struct FftwFree {
  void operator()(float* p) const { fftwf_free(p); }
};
// A zero-initialised float array from fftwf_malloc (aligned for FFTW's SIMD codelets).
using AlignedFloats = std::unique_ptr<float[], FftwFree>;
AlignedFloats alloc_floats(size_t n);

// Rounds a float count up to a multiple of 16 floats (64 bytes): sub-arrays that start at such
// offsets of an AlignedFloats keep the base alignment, which the cached plans require.
inline size_t aligned_stride(size_t n) { return (n + 15) / 16 * 16; }

enum class FftKind {
  r2c_inplace,  // real [n] -> complex [n/2+1] in one buffer of 2*(n/2+1) floats
  c2r_inplace,  // complex [n/2+1] -> real [n] (unnormalised) in one buffer
  r2c,          // out-of-place
  c2r,          // out-of-place; destroys its input
};

// The cached plan of this kind and size, created (FFTW_ESTIMATE) on first use. Execute it only on
// arrays aligned like alloc_floats() (offsets multiple of 16 floats), in-place kinds in place.
fftwf_plan fft_plan(FftKind kind, int n);

}  // namespace neraf::dsp::detail
