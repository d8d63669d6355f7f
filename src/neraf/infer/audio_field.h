#pragma once
// What render and eval need of a trained acoustic field, whichever way it is held: a run folder
// with its LibTorch model (AudioRun, infer/audio_run.h) or an exported MODEL.nrf run by neraf_rt
// (ExportedModel, infer/exported_model.h). Commands that accept `--run` or `--model` take an
// AudioField, so both give the same numbers through the same code.
//
// Positions are in the DATASET's frame in metres (SoundSpaces: [x, z, −y] of points.txt, as the
// RirSet; RAF as written), yaw in degrees (the receiver heading for SoundSpaces, the source yaw
// for RAF).
#include <torch/types.h>

#include <cstdint>
#include <vector>

#include "neraf/acoustic/calibration.h"
#include "neraf/data/rir_set.h"
#include "neraf/dsp/stft.h"
#include "neraf/geometry/vec.h"
#include "neraf/infer/run_manifest.h"  // AudioRunInfo

namespace neraf::infer {

class AudioField {
 public:
  virtual ~AudioField() = default;
  virtual const AudioRunInfo& info() const = 0;
  // N poses: mic, src [N, 3] float64 metres, yaw [N] degrees → [N, C, F, T] float32 predicted
  // log(|STFT| + 1e-3), the energy calibration applied when the field has one. Const and
  // thread-safe.
  virtual torch::Tensor predict_log_stft_batch(const torch::Tensor& mic, const torch::Tensor& src,
                                               const torch::Tensor& yaw_deg) const = 0;

  // One pose → [C, F, T].
  torch::Tensor predict_log_stft(const geometry::Vec3& mic, const geometry::Vec3& src,
                                 double yaw_deg) const;
  // Griffin-Lim waveform(s) of one pose at info().sample_rate, length hop·(T−1) (or `length`).
  std::vector<std::vector<float>> predict_waveform(const geometry::Vec3& mic,
                                                   const geometry::Vec3& src, double yaw_deg,
                                                   uint64_t seed = 0, int64_t length = 0) const;
};

// mag = clip(exp(log_stft) − 1e-3, 0, 1e4) (neraf-reference.md §4.1). Any shape.
using acoustic::log_stft_to_magnitude;
// Griffin-Lim (32 iterations, momentum 0.99, seeded random init) of [C, F, T] magnitudes →
// C waveforms of length hop·(T−1), zero-padded/cut to `length` if length > 0.
std::vector<std::vector<float>> griffin_lim_channels(const torch::Tensor& magnitude,
                                                     const dsp::StftParams& stft, uint64_t seed,
                                                     int64_t length = 0);

}  // namespace neraf::infer
