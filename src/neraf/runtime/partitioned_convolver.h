#pragma once
// Uniformly partitioned overlap-save convolution (UPOLS) with a frequency-domain delay line
// (FDL): a mono input into C output channels, block_size (B) samples per call, FFT size 2B.
// Internal to neraf_rt (the stream of neraf_rt.h is a thin C wrapper around it).
//
// The RIR [C, L] is cut into P = ceil(L / B) partitions of B samples; partition p of channel c
// is zero-padded to 2B and transformed once, off the audio thread (set_rir). Each block, the
// spectrum X_t of the last 2B input samples enters the FDL (a ring of the last P input
// spectra), and channel c's output spectrum is  Y_c = sum_p X_{t-p} * H_{c,p};  the last B
// samples of its inverse transform are the block's output (the first B wrap around: discarded).
//
// Spectra are split-complex (real parts, then imaginary parts, 64-byte aligned rows padded to
// a multiple of 16 floats), so the multiply-accumulate over partitions is a plain loop over
// bins that the compiler vectorises (-O3 -march=native).
//
// RIR changes: set_rir fills a free slot and publishes it (SlotExchange, lock-free); process()
// picks the newest slot up at the start of a block and renders that one block with both the old
// and the new partitions over the shared FDL, crossfading with a raised cosine. The new RIR's
// output is exact from the block's first sample on (the FDL already holds the input history),
// so after the one crossfade block the output is the new steady state, without a click.
#include <fftw3.h>

#include <cstddef>
#include <cstdlib>
#include <memory>

#include "neraf/runtime/slot_exchange.h"

namespace neraf::rt {

struct AlignedFree {
  void operator()(float* p) const noexcept { std::free(p); }
};
// A zero-initialised float array aligned to 64 bytes (a cache line, an AVX-512 vector).
using AlignedFloats = std::unique_ptr<float[], AlignedFree>;
AlignedFloats alloc_aligned(size_t n);  // throws std::bad_alloc

class PartitionedConvolver {
 public:
  static constexpr int kMinBlock = 16;
  static constexpr int kMaxBlock = 16384;
  static constexpr int kMaxChannels = 16;

  // Allocates every buffer (four RIR slots of max_rir_length) and plans the FFTs with
  // FFTW_MEASURE under fftw_planner_mutex(): takes milliseconds to a second, never call it on the
  // audio thread. Arguments are the caller's to validate (kMinBlock <= block_size <= kMaxBlock,
  // 1 <= channels <= kMaxChannels, max_rir_length >= 1). Throws std::bad_alloc.
  PartitionedConvolver(int channels, int block_size, size_t max_rir_length);
  ~PartitionedConvolver();
  PartitionedConvolver(const PartitionedConvolver&) = delete;
  PartitionedConvolver& operator=(const PartitionedConvolver&) = delete;

  int channels() const { return channels_; }
  int block_size() const { return block_; }
  size_t max_rir_length() const { return max_len_; }
  // Bytes of the four RIR slots (most of the memory held), for messages.
  static size_t slot_bytes(int channels, int block_size, size_t max_rir_length);

  // Producer side, ONE thread at a time (the stream's worker), never the audio thread:
  // transforms the planar RIR `rir` [channels, stride] (its first `length` <= max_rir_length
  // samples per channel; 0 is silence) into the free slot and publishes it. The next process()
  // call crossfades to it. No allocation, no locks; O(channels * P * B log B).
  void set_rir(const float* rir, size_t length, size_t stride);

  // Consumer side, the audio thread: in [block_size] mono, out planar [channels, block_size]
  // (out may overlap in). Real-time safe: no allocation, no locks, no system calls. Until a RIR
  // is published the output is silence; the first RIR fades in over one block, unless it was
  // published before the first call (then there is no earlier output to fade from).
  void process(const float* in, float* out);

 private:
  struct Slot {
    AlignedFloats spectra;  // [P, C, 2, Kp]: partition p, channel c, real row then imaginary row
    size_t n_parts = 0;     // partitions of the RIR it holds (0: silence)
  };

  // acc_ = sum over the slot's partitions of FDL spectrum * partition spectrum, every channel.
  void accumulate(const Slot& slot);
  // Renders the slot's output block into out [C, B]: written when fade is null, else mixed in
  // as out += fade * (slot's output - out) (the crossfade from what out holds).
  void render(const Slot& slot, float* out, const float* fade);

  int channels_, block_;
  size_t max_len_;
  size_t n_fft_;   // 2B
  size_t n_bins_;  // K = B + 1 bins of the real FFT
  size_t kp_;      // K rounded up to a multiple of 16 floats (64 bytes)
  size_t row_;     // 2 * kp_: one split-complex spectrum (real row, imaginary row)
  size_t p_max_;   // partitions of max_rir_length: the FDL's length
  fftwf_plan r2c_ = nullptr;  // [2B] real -> [K] interleaved complex, out of place
  fftwf_plan c2r_ = nullptr;  // [K] interleaved complex -> [2B] real, out of place

  // Audio thread's.
  AlignedFloats time_;      // [2B] the previous block's input, then this block's
  AlignedFloats spec_;      // [2K] interleaved complex: r2c output, c2r input
  AlignedFloats fdl_;       // [P_max, 2, Kp] the last P_max input spectra; fdl_head_ the newest
  AlignedFloats acc_;       // [C, 2, Kp] output spectra being accumulated
  AlignedFloats y_;         // [2B] inverse transform of one channel
  AlignedFloats fade_;      // [B] raised cosine from ~0 to 1: the new RIR's weight
  size_t fdl_head_ = 0;
  bool started_ = false;    // a block has been processed (so a new RIR must fade in)

  // Producer's.
  AlignedFloats prep_time_;  // [2B] one zero-padded partition
  AlignedFloats prep_spec_;  // [2K] its spectrum, interleaved

  Slot slots_[SlotExchange::kSlots];
  SlotExchange exchange_;
};

}  // namespace neraf::rt
