// An experiment, not a benchmark: can post-processing close neraf's T60 gap to linear
// interpolation? Scores a finished run's acoustic field on its held-out RIRs with
//   uncalibrated  the raw predictions;
//   calibrated    the run's own calibration (infer::fit_calibration, as `neraf train` fits it);
//   level         calibrated, then one more gain per (channel, bin, level band of the calibrated
//                 prediction) fitted on the same training RIRs: Σ E_gt / Σ E_pred within each band,
//                 so a bias that depends on how loud a bin is (e.g. near the 1e-3 floor) goes too;
//   smooth1/2     calibrated, then the energy after frame `early_frames` averaged over 3 / 5 frames
//                 (less scatter in the predicted tail);
// and the nearest and linear baselines, with paired per-RIR differences.
//
//   neraf_calibration_variants --run RUN --data DATA --rirs N --json OUT.json
#include <torch/torch.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "neraf/acoustic/calibration.h"
#include "neraf/eval/audio_eval.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/calibration.h"
#include "neraf/io/atomic_file.h"
#include "neraf/metrics/rir_errors.h"

using namespace neraf;

namespace {

constexpr double kLevelLow = -6.9078;  // log(1e-3): the output's floor
constexpr double kLevelWidth = 0.5;    // nepers per level band
constexpr int64_t kLevelBands = 16;

struct PostProcessing {
  torch::Tensor gain;   // [C, F, T] the run's calibration, undefined: none
  torch::Tensor level;  // [C, F, kLevelBands] or undefined
  int64_t smooth = 0;   // frames each side
  int64_t smooth_from = 0;
};

// log_stft [..., C, F, T] → the band of each value.
torch::Tensor level_band(const torch::Tensor& log_stft) {
  return ((log_stft - kLevelLow) / kLevelWidth).floor().clamp(0, kLevelBands - 1).to(torch::kLong);
}

torch::Tensor post_process(const torch::Tensor& log_stft, const PostProcessing& p) {
  if (!p.gain.defined()) return log_stft;
  torch::Tensor y = acoustic::apply_calibration(log_stft, p.gain);  // [N, C, F, T]
  if (p.level.defined()) {
    const torch::Tensor band = level_band(y);
    const torch::Tensor gains =
        torch::gather(p.level.unsqueeze(0).expand({y.size(0), -1, -1, -1}), 3, band);
    y = torch::log(acoustic::log_stft_to_magnitude(y) * gains + 1e-3);
  }
  if (p.smooth > 0) {
    const torch::Tensor e = acoustic::log_stft_to_magnitude(y).pow(2);
    const int64_t T = e.size(-1);
    torch::Tensor sum = torch::zeros_like(e), count = torch::zeros({T}, e.options());
    for (int64_t d = -p.smooth; d <= p.smooth; ++d) {
      const int64_t a = std::max<int64_t>(0, -d), b = std::min<int64_t>(T, T - d);
      sum.narrow(-1, a, b - a).add_(e.narrow(-1, a + d, b - a));
      count.narrow(0, a, b - a).add_(1);
    }
    const torch::Tensor late = (torch::arange(T) >= p.smooth_from).to(e.dtype());
    y = torch::log((e * (1 - late) + sum / count * late).sqrt() + 1e-3);
  }
  return y;
}

class PostProcessedField final : public infer::AudioField {
 public:
  PostProcessedField(const infer::AudioRun& run, PostProcessing p) : run_(run), p_(std::move(p)) {}
  const infer::AudioRunInfo& info() const override { return run_.info(); }
  torch::Tensor predict_log_stft_batch(const torch::Tensor& mic, const torch::Tensor& src,
                                       const torch::Tensor& yaw) const override {
    return post_process(run_.predict_log_stft_batch(mic, src, yaw), p_);
  }

 private:
  const infer::AudioRun& run_;
  PostProcessing p_;
};

// Gains per (channel, bin, level band) that restore the training RIRs' energy in each band.
torch::Tensor fit_level_gains(const infer::AudioRun& run, const data::RirSet& rirs,
                              const std::vector<int64_t>& train, const torch::Tensor& gain) {
  const int64_t stride = std::max<int64_t>(1, (static_cast<int64_t>(train.size()) + 511) / 512);
  std::vector<torch::Tensor> preds, truths;
  for (size_t k = 0; k < train.size(); k += static_cast<size_t>(stride)) {
    const int64_t i = train[k];
    preds.push_back(
        run.predict_pose(rirs.mic_positions[i], rirs.source_positions[i], rirs.rots[i]).cpu());
    truths.push_back(rirs.features(i).to(torch::kFloat32));
  }
  const torch::Tensor pred = acoustic::apply_calibration(torch::stack(preds), gain);  // [N,C,F,T]
  const torch::Tensor truth = torch::stack(truths);
  const int64_t C = pred.size(1), F = pred.size(2);
  auto by_channel_bin = [&](const torch::Tensor& x) {  // [N, C, F, T] → [C, F, N·T]
    return x.permute({1, 2, 0, 3}).reshape({C, F, -1});
  };
  const torch::Tensor band = by_channel_bin(level_band(pred));
  auto band_sum = [&](const torch::Tensor& log_stft) {
    const torch::Tensor energy =
        acoustic::log_stft_to_magnitude(log_stft).to(torch::kFloat64).pow(2);
    return torch::zeros({C, F, kLevelBands}, torch::kFloat64)
        .scatter_add_(2, band, by_channel_bin(energy));
  };
  const torch::Tensor pred_sum = band_sum(pred), truth_sum = band_sum(truth);
  return torch::where((pred_sum > 0) & (truth_sum > 0), (truth_sum / pred_sum).sqrt(),
                      torch::ones_like(pred_sum))
      .clamp(1 / acoustic::kMaxCalibrationGain, acoustic::kMaxCalibrationGain)
      .to(torch::kFloat32);
}

std::vector<double> errors(const eval::AudioMethodEval& m, const std::string& metric) {
  std::vector<double> v;
  for (const metrics::RirErrors& r : m.per_rir)
    v.push_back(metric == "t60_error_pct"  ? r.t60_error_pct
                : metric == "c50_error_db" ? r.c50_error_db
                                           : r.edt_error_s);
  return v;
}

nlohmann::json paired(const eval::AudioMethodEval& a, const eval::AudioMethodEval& b) {
  nlohmann::json out;
  for (const char* metric : {"t60_error_pct", "c50_error_db", "edt_error_s"}) {
    const metrics::PairedDifference d =
        metrics::paired_difference(errors(a, metric), errors(b, metric));
    out[metric] = {{"mean_difference", d.mean}, {"standard_error", d.standard_error}};
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Scores a run's acoustic field on its held-out RIRs with other post-processings "
      "of its predictions (bench/calibration_variants.cpp says which) beside the "
      "nearest and linear baselines, paired per RIR."};
  std::string run_dir, data_dir, out_path;
  int64_t n_test = 1000;
  app.add_option("--run", run_dir, "Run folder made by neraf train")->required();
  app.add_option("--data", data_dir, "The run's dataset")->required();
  app.add_option("--rirs", n_test, "Score the first N held-out RIRs")
      ->check(CLI::Range(int64_t{1}, int64_t{1} << 40))
      ->capture_default_str();
  app.add_option("--json", out_path, "Output JSON file")->required();
  CLI11_PARSE(app, argc, argv);
  try {
    torch::NoGradGuard no_grad;
    const data::RirSet rirs = data::load_rir_set(data_dir, data::RirLoadOptions{});
    const infer::AudioRun run = infer::load_audio_run(run_dir, torch::kCPU, "",
                                                      nerf::Precision::fp32, /*calibrated=*/false);
    const infer::TrainConfig& config = run.run().config;
    const std::vector<int64_t> train =
        infer::audio_train_subset(rirs, config.audio.fraction, config.seed);

    PostProcessing calibrated;
    calibrated.gain = infer::fit_calibration(run, rirs);
    PostProcessing level = calibrated;
    level.level = fit_level_gains(run, rirs, train, calibrated.gain);
    PostProcessing smooth1 = calibrated, smooth2 = calibrated;
    smooth1.smooth = 1;
    smooth2.smooth = 2;
    smooth1.smooth_from = smooth2.smooth_from = config.audio.early_frames;

    eval::AudioEvalOptions options;
    options.num_images = 0;
    options.seed = config.seed;
    options.max_rirs = n_test;
    const std::vector<int64_t> test(
        rirs.test.begin(), rirs.test.begin() + std::min<int64_t>(n_test, rirs.test.size()));
    std::vector<eval::AudioMethodEval> methods;
    for (const auto& [name, p] :
         std::vector<std::pair<std::string, PostProcessing>>{{"uncalibrated", {}},
                                                             {"calibrated", calibrated},
                                                             {"level", level},
                                                             {"smooth1", smooth1},
                                                             {"smooth2", smooth2}})
      methods.push_back(
          eval::evaluate_audio_model(PostProcessedField(run, p), rirs, test, name, options));
    const eval::AudioEval baselines =
        eval::evaluate_audio(PostProcessedField(run, calibrated), rirs, train, options);
    for (const eval::AudioMethodEval& m : baselines.methods)
      if (m.name == "nearest" || m.name == "linear") methods.push_back(m);

    std::string command = "neraf_calibration_variants";
    for (int i = 1; i < argc; ++i) command += std::string(" ") + argv[i];
    nlohmann::json out = {{"command", command}, {"n_rirs", test.size()}};
    for (const eval::AudioMethodEval& m : methods) {
      nlohmann::json j = eval::to_json(m.summary);
      double bias = 0;
      int64_t valid = 0;
      for (const metrics::RirErrors& r : m.per_rir)
        if (r.t60_pred_s > 0 && r.t60_gt_s > 0) {
          bias += 100 * (r.t60_pred_s / r.t60_gt_s - 1);
          ++valid;
        }
      j["t60_signed_error_pct"] = valid > 0 ? bias / static_cast<double>(valid) : 0.0;
      if (m.name != "calibrated") j["minus_calibrated"] = paired(m, methods[1]);
      for (const eval::AudioMethodEval& b : methods)
        if (b.name == "nearest" || b.name == "linear") j["minus_" + b.name] = paired(m, b);
      out["methods"][m.name] = j;
      std::printf("%-13s T60 %.3f %%  C50 %.4f dB  EDT %.5f s  T60 signed %+.2f %%\n",
                  m.name.c_str(), m.summary.t60_error_pct.mean, m.summary.c50_error_db.mean,
                  m.summary.edt_error_s.mean, j["t60_signed_error_pct"].get<double>());
    }
    io::write_text_atomically(out_path, out.dump(2) + "\n");
    std::printf("wrote %s\n", out_path.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
