#pragma once
// Inference on a trained run's acoustic field (for `neraf render rir`, `render loudness`,
// `auralize --run`, `eval`).
//
// Usage (render engineer):
//   #include "neraf/train/audio_run.h"
//   train::AudioRun run = train::load_audio_run("runs/demo");          // latest checkpoint
//   const train::AudioRunInfo& info = run.info();  // sample_rate, stft, max_len, channels, aabb
//   torch::Tensor log_stft = run.predict_log_stft({1.0, 1.5, 2.0}, {3.0, 1.5, 0.5}, 90.0);
//   // [C, F, T] float32 = predicted log(|STFT| + 1e-3); magnitude for Griffin-Lim:
//   torch::Tensor mag = train::log_stft_to_magnitude(log_stft);         // clip(exp − 1e-3, 0, 1e4)
//   std::vector<std::vector<float>> wave = run.predict_waveform(mic, src, yaw);  // GL, C channels
// Positions are in the DATASET's frame in metres (SoundSpaces: [x, z, −y] of points.txt, as the
// RirSet; RAF as written), yaw in degrees (the receiver heading for SoundSpaces, the source yaw for
// RAF), encoded as ((cos+1)/2, 0.5, (sin+1)/2). Positions outside the train audio aabb are zeroed
// (the reference's rule) — the prediction is then meaningless; check info().aabb.
// Batch many poses with predict_log_stft_batch (one NAcF call per pose, the scene feature is
// computed once at load).
#include <torch/torch.h>

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/acoustic/acoustic_model.h"
#include "neraf/acoustic/calibration.h"
#include "neraf/data/rir_set.h"
#include "neraf/dsp/stft.h"
#include "neraf/geometry/vec.h"
#include "neraf/train/run.h"

namespace neraf::train {

struct AudioRunInfo {
  data::AudioLayout layout = data::AudioLayout::soundspaces;
  int sample_rate = 22050;  // 22050 SoundSpaces, 48000 RAF
  dsp::StftParams stft;     // soundspaces() / raf()
  int64_t n_freq = 257;
  int64_t max_len = 78;         // frames per RIR (T)
  int channels = 2;             // C
  int64_t waveform_length = 0;  // GT eval waveform length (SoundSpaces max_len·hop, RAF 15360)
  data::Aabb aabb;              // train audio aabb (positions are normalised with it)
};

// The "audio" entry of RUN/data.json (layout, counts, a hash of the RIR ids/poses, STFT sizes,
// aabb) and its inverse. Loading a run or resuming checks it against the dataset.
nlohmann::json make_audio_manifest(const data::RirSet& rirs);
AudioRunInfo audio_info_from_manifest(const nlohmann::json& audio, const std::string& where);
// neraf::Error "<where>: ... differs (key)" when `rirs` is not the dataset of `manifest`.
void check_audio_manifest(const nlohmann::json& manifest, const data::RirSet& rirs,
                          const std::string& where);
// neraf::Error when `rirs` cannot be scored against the run of `manifest`: another layout, sample
// rate, channel count or STFT (any set of the same room in the same format passes).
void check_same_room_format(const nlohmann::json& manifest, const data::RirSet& rirs,
                            const std::string& where);

// mag = clip(exp(log_stft) − 1e-3, 0, 1e4) (neraf-reference.md §4.1). Any shape.
using acoustic::log_stft_to_magnitude;
// Griffin-Lim (32 iterations, momentum 0.99, seeded random init) of [C, F, T] magnitudes →
// C waveforms of length hop·(T−1), zero-padded/cut to `length` if length > 0.
std::vector<std::vector<float>> griffin_lim_channels(const torch::Tensor& magnitude,
                                                     const dsp::StftParams& stft, uint64_t seed,
                                                     int64_t length = 0);

class AudioRun {
 public:
  AudioRun() = default;
  const AudioRunInfo& info() const { return info_; }
  const LoadedRun& run() const { return run_; }
  int64_t step() const { return run_.step; }

  // One pose → [C, F, T] predicted log-magnitude STFT (no autograd, eval mode).
  torch::Tensor predict_log_stft(const geometry::Vec3& mic, const geometry::Vec3& src,
                                 double yaw_deg) const;
  // N poses: mic, src [N, 3] float64 metres, yaw [N] degrees → [N, C, F, T].
  torch::Tensor predict_log_stft_batch(const torch::Tensor& mic, const torch::Tensor& src,
                                       const torch::Tensor& yaw_deg) const;
  // Griffin-Lim waveform(s) of one pose at info().sample_rate, length hop·(T−1) (or `length`).
  std::vector<std::vector<float>> predict_waveform(const geometry::Vec3& mic,
                                                   const geometry::Vec3& src, double yaw_deg,
                                                   uint64_t seed = 0, int64_t length = 0) const;

  // Low level: normalised inputs (mic_norm, src_norm, rot: [3] each) → [C, F, T], with the
  // checkpoint's energy calibration applied when it has one.
  torch::Tensor predict_normalised(const torch::Tensor& mic_norm, const torch::Tensor& src_norm,
                                   const torch::Tensor& rot) const;
  acoustic::AcousticModel& model() const { return model_; }

 private:
  friend AudioRun load_audio_run(const std::string&, torch::Device, const std::string&);
  LoadedRun run_;  // run_.model is the radiance field (nullptr-free only for vision/joint runs)
  AudioRunInfo info_;
  mutable acoustic::AcousticModel model_{nullptr};
  torch::Tensor feature_;  // [G] scene feature (eval-mode ResNet3D on the saved grid) or undefined
  torch::Tensor calibration_;  // [C, F, T] energy gains (acoustic/calibration.h) or undefined
};

// Loads RUN (latest checkpoint, or `checkpoint`) with its acoustic field. neraf::Error when the
// run has no acoustic branch (modality vision) or is broken.
AudioRun load_audio_run(const std::string& run_dir, torch::Device device = torch::kCPU,
                        const std::string& checkpoint = "");

}  // namespace neraf::train
