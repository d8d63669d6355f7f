#pragma once
// NAcF's input encodings without LibTorch, computed as src/neraf/acoustic/nacf.cpp does (same
// formulas, same precision: positions, rot and relative geometry in double, the time index in
// float), so the runtime's inputs match the training code's to float rounding.
//
//   time      x = t/(T − 1) (float) → [sin(2πx·f_k), sin(2πx·f_k + π/2), x], 10 frequencies  (21)
//   position  p normalised by the box (zero vector outside), same encoding per axis, dim-major (63)
//   rot       ((cosθ+1)/2, 0.5, (sinθ+1)/2) → real SH degree 4 of 2v − 1 (tcnn's mapping) (16)
//   relative  direction, elevation and distance of the source from the microphone, in metres   (22)
// The frequencies are 2^linspace(0, max_exp, 10) in float32 as torch computes them (then promoted
// to double for positions).
#include <array>
#include <cstdint>

namespace neraf::rt {

constexpr int kNumFrequencies = 10;

// f_k as float32: torch.linspace(0, max_exp, 10) (float32, its two-sided formula), then powf(2, .).
std::array<float, kNumFrequencies> encoding_frequencies(double max_exp);

// data::normalize_position: (p − min)/(max − min); all three zero unless each lies in (0, 1).
std::array<double, 3> normalize_position(const double p[3], const std::array<double, 3>& box_min,
                                         const std::array<double, 3>& box_max);

// ((cosθ+1)/2, 0.5, (sinθ+1)/2), θ = yaw_deg·π/180 (infer::AudioRun::predict_log_stft_batch).
std::array<double, 3> rot_from_yaw(double yaw_deg);

// out[21]: frame t of T (t/(T − 1) in float, the encoding in float).
void encode_time(int t, int n_frames, const std::array<float, kNumFrequencies>& freqs, float* out);

// out[63] (double): the encoding of a normalised position.
void encode_position(const std::array<double, 3>& p,
                     const std::array<float, kNumFrequencies>& freqs, double* out);

// out[16] (double): SH degree 4 of 2·rot − 1.
void encode_rot(const std::array<double, 3>& rot, double* out);

// out[22] (double): acoustic::encode_relative_geometry for one pose, from the positions in metres
// (not the normalised ones, which are zero outside the box); extent_m: the box's size.
void encode_relative_geometry(const std::array<double, 3>& mic_m,
                              const std::array<double, 3>& src_m, const std::array<double, 3>& rot,
                              const std::array<double, 3>& extent_m, double* out);

}  // namespace neraf::rt
