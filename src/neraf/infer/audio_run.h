#pragma once
// Inference on a trained run's acoustic field (for `neraf render rir`, `render loudness`,
// `auralize --run`, `eval`).
//
// Usage:
//   #include "neraf/infer/audio_run.h"
//   const infer::AudioRun run = infer::load_audio_run("runs/demo");    // latest checkpoint
//   const infer::AudioRunInfo& info = run.info();  // sample_rate, stft, max_len, channels, aabb
//   torch::Tensor log_stft = run.predict_log_stft({1.0, 1.5, 2.0}, {3.0, 1.5, 0.5}, 90.0);
//   // [C, F, T] float32 = predicted log(|STFT| + 1e-3); magnitude for Griffin-Lim:
//   torch::Tensor mag = infer::log_stft_to_magnitude(log_stft);         // clip(exp − 1e-3, 0, 1e4)
//   std::vector<std::vector<float>> wave = run.predict_waveform(mic, src, yaw);  // GL, C channels
// Positions are in the DATASET's frame in metres (SoundSpaces: [x, z, −y] of points.txt, as the
// RirSet; RAF as written), yaw in degrees (the receiver heading for SoundSpaces, the source yaw for
// RAF), encoded as ((cos+1)/2, 0.5, (sin+1)/2). Positions outside the train audio aabb get a zero
// position encoding (the reference's rule) — the prediction is then unreliable; check info().aabb.
// The relative-geometry inputs (presets cpu) are computed from the metres, so they stay right.
// Batch many poses with predict_log_stft_batch (one NAcF call per pose, the scene feature is
// computed once at load). Queries run NAcF in fp32 whatever precision trained the run (unless
// load_audio_run is asked for bf16).
//
// Threads: every query is const and may run from several threads at once on one AudioRun. The
// model is put in eval mode once, at load; a query runs NAcF on the scene feature computed then
// (AcousticModelImpl::render_stft_with_feature: no module state is touched, no train/eval
// switch; NAcF has no BatchNorm or dropout) under a thread-local torch::NoGradGuard.
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
#include "neraf/infer/audio_field.h"
#include "neraf/infer/run.h"
#include "neraf/nerf/config.h"

namespace neraf::infer {

// The "audio" entry of RUN/data.json (layout, counts, a hash of the RIR ids/poses, STFT sizes,
// aabb); its inverse is audio_info_from_manifest (run_manifest.h). Loading a run or resuming
// checks it against the dataset.
nlohmann::json make_audio_manifest(const data::RirSet& rirs);
// neraf::Error "<where>: ... differs (key)" when `rirs` is not the dataset of `manifest`.
void check_audio_manifest(const nlohmann::json& manifest, const data::RirSet& rirs,
                          const std::string& where);
// neraf::Error when `rirs` cannot be scored against the run of `manifest`: another layout, sample
// rate, channel count or STFT (any set of the same room in the same format passes).
void check_same_room_format(const nlohmann::json& manifest, const data::RirSet& rirs,
                            const std::string& where);

// The acoustic model options of a run: the preset's (`config.preset`) sized to the data, with the
// AudioConfig overrides (grid mode and features, resolution, cells per update, NAcF width,
// relative geometry), `audio_aabb` as the box NAcF normalises positions by and `world_to_field`
// as the map of those metres into the radiance field's frame (per-query grid features; from
// the run's data manifest, world_to_field below).
acoustic::AcousticModelOptions audio_model_options(
    const TrainConfig& config, int64_t channels, int64_t n_freq, int64_t max_len,
    const data::Aabb& audio_aabb,
    const acoustic::WorldToField& world_to_field = acoustic::kIdentityWorldToField);

// The seeded subset of `rirs.train` used for training (--audio-fraction): all of it for
// fraction 1, else round(fraction·N) (at least 1) indices drawn without replacement with `seed`,
// in ascending order.
std::vector<int64_t> audio_train_subset(const data::RirSet& rirs, double fraction, uint64_t seed);

class AudioRun final : public AudioField {
 public:
  AudioRun() = default;
  const AudioRunInfo& info() const override { return info_; }
  const LoadedRun& run() const { return run_; }
  int64_t step() const { return run_.step; }
  // The scene this field answers for: 0 for a one-scene run; for a multi-scene run the one
  // load_audio_run was asked for (run().manifest is then that scene's manifest).
  int64_t scene() const { return scene_; }

  // N poses: mic, src [N, 3] float64 metres, yaw [N] degrees → [N, C, F, T] (no autograd).
  torch::Tensor predict_log_stft_batch(const torch::Tensor& mic, const torch::Tensor& src,
                                       const torch::Tensor& yaw_deg) const override;

  // Low level: one pose (mic_m, src_m: [3] metres, float64; rot: [3] as the RirSet stores it) →
  // [C, F, T], with the energy calibration applied when the run was loaded with one.
  torch::Tensor predict_pose(const torch::Tensor& mic_m, const torch::Tensor& src_m,
                             const torch::Tensor& rot) const;

  // What a query reads, for exporting the model: the acoustic model (eval mode; read-only), the
  // scene features (acoustic_model.h; none for grid mode none) and the [C, F, T] energy gains
  // (undefined when the run has no calibration).
  const acoustic::AcousticModel& model() const { return model_; }
  const acoustic::SceneFeatures& scene_features() const { return features_; }
  const torch::Tensor& calibration() const { return calibration_; }

 private:
  friend AudioRun load_audio_run(const std::string&, torch::Device, const std::string&,
                                 nerf::Precision, bool, int64_t);
  LoadedRun run_;
  int64_t scene_ = 0;  // run_.model is the radiance field (nullptr-free only for vision/joint runs)
  AudioRunInfo info_;
  acoustic::AcousticModel model_{nullptr};  // eval mode from load on; queries only read it
  acoustic::SceneFeatures features_;        // eval-mode ResNet3D on the saved grid
  torch::Tensor calibration_;  // [C, F, T] energy gains (acoustic/calibration.h) or undefined
};

// Loads RUN (latest checkpoint, or `checkpoint`) with its acoustic field. Queries run NAcF's
// trunk in `precision` (fp32 by default, whatever trained the run; bf16: as a bf16 run trained,
// on machines with native bf16) and apply the checkpoint's energy calibration (calibration.h)
// when `calibrated` and the run has one (a warning when the run uses calibration but this step
// was never calibrated). neraf::Error when the run has no acoustic branch (modality vision) or
// is broken. A multi-scene run (run.h, is_multiscene) needs `scene` (0..N−1: that scene's grid,
// box, calibration and manifest; see find_scene); −1 on it is refused naming --scene.
AudioRun load_audio_run(const std::string& run_dir, torch::Device device = torch::kCPU,
                        const std::string& checkpoint = "",
                        nerf::Precision precision = nerf::Precision::fp32, bool calibrated = true,
                        int64_t scene = -1);

}  // namespace neraf::infer
