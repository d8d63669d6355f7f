#include "neraf/infer/calibration.h"

#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <optional>

#include "neraf/acoustic/calibration.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/metrics/room_acoustics.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::infer {

namespace {
void stop_if_asked(const std::atomic<bool>* stop) {
  if (stop && stop->load())
    throw Interrupted(
        "calibration stopped; nothing was written (neraf calibrate --run RUN "
        "finishes it)");
}
}  // namespace

torch::Tensor fit_calibration(const AudioRun& run, const data::RirSet& all_frames,
                              const std::atomic<bool>* stop) {
  const TrainConfig& config = run.run().config;
  // A multi-scene run's scene: fitted on its own frames, as it predicts them.
  std::optional<data::RirSet> cut;
  if (run.info().max_len < all_frames.max_len)
    cut = data::first_frames(all_frames, run.info().max_len);
  const data::RirSet& rirs = cut ? *cut : all_frames;
  const int64_t C = rirs.channels, F = rirs.n_freq, T = rirs.max_len;
  if (!config.audio.energy_calibration) return torch::ones({C, F, T});
  torch::NoGradGuard no_grad;
  const std::vector<int64_t> train = audio_train_subset(rirs, config.audio.fraction, config.seed);
  const int64_t n = static_cast<int64_t>(train.size());
  const int64_t stride = std::max<int64_t>(1, (n + 511) / 512);  // at most 512 RIRs
  const int64_t sampled = (n + stride - 1) / stride;
  const int64_t balance_stride = std::max<int64_t>(1, (sampled + 63) / 64);  // ≤ 64 of those
  torch::Tensor gt_energy = torch::zeros({C, F, T}, torch::kFloat64),
                pred_energy = gt_energy.clone();
  std::vector<std::pair<int64_t, torch::Tensor>> preds;  // (RIR, [C, F, T]) for the balance
  for (int64_t k = 0; k < n; k += stride) {
    stop_if_asked(stop);
    const int64_t i = train[static_cast<size_t>(k)];
    const torch::Tensor pred =
        run.predict_pose(rirs.mic_positions[i], rirs.source_positions[i], rirs.rots[i])
            .cpu();  // [C, F, T]
    pred_energy += acoustic::bin_energy(pred);
    gt_energy += acoustic::bin_energy(rirs.features(i));
    if ((k / stride) % balance_stride == 0) preds.emplace_back(i, pred);
  }
  const torch::Tensor gain = acoustic::calibration_gain(gt_energy, pred_energy);

  // Early/late balance: C50 of the calibrated predictions rendered as evaluation renders them
  // (Griffin-Lim, seeded) against the training waveforms, per channel (calibration.h).
  const double fs = rirs.sample_rate;
  torch::Tensor delta = torch::zeros({C}, torch::kFloat64);
  std::vector<int64_t> counted(static_cast<size_t>(C), 0);
  for (size_t r = 0; r < preds.size(); ++r) {
    stop_if_asked(stop);
    const auto& [i, pred] = preds[r];
    const torch::Tensor gt = rirs.waveform(i).contiguous();  // [C, L]
    const auto wave =
        griffin_lim_channels(log_stft_to_magnitude(acoustic::apply_calibration(pred, gain)),
                             rirs.stft, config.seed + r, gt.size(1));
    for (int64_t c = 0; c < C; ++c) {
      const float* g = gt[c].data_ptr<float>();
      const double d = metrics::measure_c50(std::vector<float>(g, g + gt.size(1)), fs) -
                       metrics::measure_c50(wave[static_cast<size_t>(c)], fs);
      if (!std::isfinite(d)) continue;
      delta[c] += d;
      ++counted[static_cast<size_t>(c)];
    }
  }
  for (int64_t c = 0; c < C; ++c)
    if (counted[static_cast<size_t>(c)] > 0)
      delta[c] /= static_cast<double>(counted[static_cast<size_t>(c)]);
  return acoustic::with_early_balance(gain, delta, rirs.stft.hop_length,
                                      metrics::c50_split_sample(fs));
}

void save_calibration(const std::string& checkpoint, int64_t step, const torch::Tensor& gains) {
  save_calibration(checkpoint, step, std::vector<torch::Tensor>{gains});
}

void save_calibration(const std::string& checkpoint, int64_t step,
                      const std::vector<torch::Tensor>& scene_gains) {
  torch::serialize::OutputArchive a;
  a.write("step", torch::tensor(step, torch::kInt64));
  for (size_t s = 0; s < scene_gains.size(); ++s)
    a.write(scene_key("gains", static_cast<int64_t>(s)),
            scene_gains[s].to(torch::kCPU, torch::kFloat32).contiguous());
  save_archive(a, calibration_path(checkpoint));
}

std::optional<torch::Tensor> load_calibration(const std::string& checkpoint, int64_t step,
                                              int64_t scene) {
  const std::string path = calibration_path(checkpoint);
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  torch::serialize::InputArchive a;
  load_archive(a, path);
  torch::Tensor stored_step, gains;
  try {
    a.read("step", stored_step);
    a.read(scene_key("gains", scene), gains);
  } catch (const c10::Error&) {
    throw Error(path + ": not a calibration file; delete it and run neraf calibrate");
  }
  require(stored_step.numel() == 1 && stored_step.item<int64_t>() == step,
          path + ": fitted for another step than " + checkpoint +
              "; delete it and run neraf calibrate");
  require(gains.dim() == 3 && torch::isfinite(gains).all().item<bool>(),
          path + ": damaged gains; delete it and run neraf calibrate");
  return gains;
}

std::string calibrate_run(const std::string& run_dir, const data::RirSet& rirs,
                          const std::string& checkpoint, const std::atomic<bool>* stop) {
  return calibrate_run(run_dir, std::vector<const data::RirSet*>{&rirs}, checkpoint, stop);
}

std::string calibrate_run(const std::string& run_dir,
                          const std::vector<const data::RirSet*>& scenes,
                          const std::string& checkpoint, const std::atomic<bool>* stop) {
  std::vector<torch::Tensor> gains;
  std::string written, step_checkpoint;
  int64_t step = 0;
  for (size_t s = 0; s < scenes.size(); ++s) {
    // A one-scene run is loaded as such (scene −1); scene s of a multi-scene run by its index.
    const AudioRun run =
        load_audio_run(run_dir, torch::kCPU, checkpoint, nerf::Precision::fp32,
                       /*calibrated=*/false, scenes.size() > 1 ? static_cast<int64_t>(s) : -1);
    check_audio_manifest(run.run().manifest["audio"], *scenes[s], run_dir + "/data.json");
    gains.push_back(fit_calibration(run, *scenes[s], stop));
    step_checkpoint = run.run().checkpoint;
    step = run.step();
  }
  save_calibration(step_checkpoint, step, gains);
  return calibration_path(step_checkpoint);
}

}  // namespace neraf::infer
