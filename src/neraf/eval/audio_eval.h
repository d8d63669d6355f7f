#pragma once
// Audio evaluation of a run on the RirSet test split, with the published evaluator's procedure
// (neraf-reference.md §4.1): predicted log-STFT [C, F, T] per test RIR → magnitude
// clip(exp(pred) − 1e-3, 0, 1e4) → Griffin-Lim (32 iterations, momentum 0.99, random initial
// phase seeded with `seed` + test index) → zero-padded to the ground-truth waveform's length →
// metrics::compare_rirs with the layout's variant (soundspaces / raf).
//
// Baselines on the same split (no learning):
//   nearest  the training RIR (of the run's train subset) with the same heading and the same
//            source position (within 1 mm) whose mic is closest (Euclidean, metres); its
//            ground-truth WAVEFORM is the prediction. Without a same-heading-and-source candidate
//            it falls back to same heading (distance = mic distance + source distance), then to
//            any RIR with that combined distance.
//   linear   the k = min(4, candidates) nearest training RIRs of the same candidate set (≥ 1;
//            2-4 whenever the set allows), weights w_i = 1/(d_i + 1e-3 m) normalised to sum 1
//            (an exact pose match, d < 1e-6, takes weight 1); the prediction is Griffin-Lim (same
//            settings as neraf) of Σ w_i·mag_i, mag_i = clip(exp(logSTFT_i) − 1e-3, 0, 1e4) the
//            training features (padded to max_len as for training).
// And a reference row, not a method: griffin_lim_floor, the test RIR's own measured magnitudes
// (its features, cut or padded to max_len as for training) through the same Griffin-Lim: what
// a field that predicted every magnitude exactly would score. Every Griffin-Lim row's error
// contains this floor; `nearest`, a measured waveform, does not.
// Metrics per method: mean (and sample std) of t60_error_pct, c50_error_db, edt_error_s,
// stft_error, and invalid_t60 (fraction of RIRs with an invalid T60), n_rirs.
//
// Post-processing, stated per method (AudioMethodEval::post_processing, the table's last column
// and the JSON's "post_processing"), so that a comparison through Griffin-Lim is read fairly:
// neraf's prediction may carry the run's energy calibration and early/late balance, fitted on its
// training RIRs (infer/calibration.h); the linear baseline never does. With a calibrated run,
// eval therefore also scores the same field without them ("neraf_uncalibrated", options
// .uncalibrated), with its own paired differences against each baseline.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/data/rir_set.h"
#include "neraf/infer/audio_field.h"
#include "neraf/metrics/rir_errors.h"

namespace neraf::eval {

// Candidate training RIRs for the pose of `query`, ordered by distance (closest first), at most
// `k` (k ≤ 0: all). `train` are indices into train_set.rirs. Distances in `dist` (metres).
std::vector<int64_t> nearest_training_rirs(const data::RirSet& train_set,
                                           const std::vector<int64_t>& train,
                                           const data::Rir& query, int64_t k,
                                           std::vector<double>* dist = nullptr);

// What a method's waveform is (AudioMethodEval::post_processing).
inline constexpr const char* kCalibratedGriffinLim =
    "griffin_lim_calibrated";  // GL of the prediction × the gains fitted on the training RIRs
inline constexpr const char* kGriffinLim = "griffin_lim";              // GL of the raw magnitudes
inline constexpr const char* kMeasuredWaveform = "measured_waveform";  // a training RIR as it is
// The name of the uncalibrated neraf row.
inline constexpr const char* kUncalibratedName = "neraf_uncalibrated";
// The name of the reference row: the measured magnitudes through Griffin-Lim.
inline constexpr const char* kGriffinLimFloorName = "griffin_lim_floor";

struct AudioEvalOptions {
  std::string out_dir;     // per-RIR CSV (audio_per_rir.csv) and PNGs (audio_XXX.png) here
  int64_t num_images = 4;  // predicted | ground-truth log-STFT PNGs for the first N test RIRs
  bool baselines = true;   // also score nearest, linear and griffin_lim_floor
  int64_t max_rirs = -1;   // only the first N test RIRs (−1: all)
  uint64_t seed = 0;       // Griffin-Lim initial phases
  bool progress = true;
  // What `run`'s predictions carry: kCalibratedGriffinLim when it applies its calibration.
  std::string neraf_post_processing = kGriffinLim;
  // The same field without its calibration (infer::load_audio_run(..., calibrated = false)),
  // scored as kUncalibratedName beside "neraf"; nullptr: not scored (an uncalibrated run).
  const infer::AudioField* uncalibrated = nullptr;
};

struct AudioMethodEval {
  std::string name;  // "neraf", "nearest", "linear" or an ablation label
  std::vector<metrics::RirErrors> per_rir;
  metrics::RirErrorSummary summary;
  double seconds = 0;  // wall time of the scoring (the baselines and the floor: of all together)
  std::string post_processing = kGriffinLim;  // kCalibratedGriffinLim, kGriffinLim, ...
};

struct AudioEval {
  std::vector<std::string> rir_ids;  // test RIRs evaluated, in order
  std::vector<AudioMethodEval> methods;
  double seconds = 0;
};

// `train_subset`: the training RIRs the baselines may use (the run's --audio-fraction subset).
// Scores rirs.test (the first options.max_rirs of it).
AudioEval evaluate_audio(const infer::AudioField& run, const data::RirSet& rirs,
                         const std::vector<int64_t>& train_subset,
                         const AudioEvalOptions& options = {});
// Same for the RIRs `test` of another set of the same room (new microphone positions, e.g.
// `neraf synth --mics random`); the baselines draw on `train_subset` of `train_set`.
AudioEval evaluate_audio(const infer::AudioField& run, const data::RirSet& train_set,
                         const std::vector<int64_t>& train_subset, const data::RirSet& test_set,
                         const std::vector<int64_t>& test, const AudioEvalOptions& options = {});
// neraf only (for ablation runs): method named `label`, its post_processing `post_processing`.
AudioMethodEval evaluate_audio_model(const infer::AudioField& run, const data::RirSet& rirs,
                                     const std::vector<int64_t>& test, const std::string& label,
                                     const AudioEvalOptions& options,
                                     const std::string& post_processing = kGriffinLim);

// {"t60_error_pct", "c50_error_db", "edt_error_s", "stft_error", "invalid_t60", "n_rirs",
//  "<key>_std" ...}
nlohmann::json to_json(const metrics::RirErrorSummary& s);
// {"neraf": {..., "seconds", "post_processing"}, "neraf_uncalibrated": {...}, "nearest": {...},
//  "linear": {...}, "griffin_lim_floor": {...}}
nlohmann::json to_json(const AudioEval& e);
// Method `first` against each of `others` present in `e`, on the same RIRs
// (metrics::paired_difference of the T60, C50 and EDT errors, first − other):
// {"nearest": {"t60_error_pct": {"mean_difference", "standard_error", "neraf_better" (RIRs where
// `first` is better), "n"}, ...}, "linear": {...}}; empty when `first` or all `others` are absent.
nlohmann::json paired_to_json(const AudioEval& e, const std::string& first = "neraf",
                              const std::vector<std::string>& others = {"nearest", "linear"});
// The same as lines to print under the table ("" when there is nothing to pair).
std::string paired_table(const AudioEval& e, const std::string& first = "neraf",
                         const std::vector<std::string>& others = {"nearest", "linear"});

// How the training of an ablation run (`other_*`) differs from the run it is compared with
// (`main_*`) beyond the ablation knobs: "" when they trained alike, else the first differing
// setting as "<file> <key>: <other's value> vs <main's value>" (e.g. `config.json modality:
// "audio" vs "joint"`). *_config: RUN/config.json (infer::to_json of the TrainConfig); *_data:
// RUN/data.json. Not compared: the ablation knobs (ablation_knobs()), what does not change what
// is trained (threads, save_every, eval_rays_per_chunk, audio.cache_dir) and the dataset's path
// (data.json "data"; the manifests beside it compare its contents). audio.vision_run compares
// the folders, however written.
std::string training_difference(const nlohmann::json& main_config, const nlohmann::json& main_data,
                                const nlohmann::json& other_config,
                                const nlohmann::json& other_data);
// The config.json keys an ablation may change: audio.grid, audio.grid_features,
// audio.grid_resolution, audio.relative_geometry, audio.loss, audio.position_max_freq_exp,
// audio.decay_heads, audio.average_fraction.
std::vector<std::string> ablation_knobs();
// Writes "rir_id,method,t60_error_pct,c50_error_db,edt_error_s,stft_error,invalid_t60,
// t60_pred_s,t60_gt_s,c50_pred_db,c50_gt_db" rows (the last four: channel means of the measured
// values, to show a bias).
void write_audio_csv(const std::string& path, const AudioEval& e);
// A fixed-width table of the methods' means, each row with its post-processing.
std::string audio_table(const std::vector<AudioMethodEval>& methods);

// [C, F, T] log-STFTs → one PNG: prediction (left) | ground truth (right), channel 0, low
// frequencies at the bottom, common colour scale (viridis), each pixel 3×3.
void write_stft_comparison_png(const std::string& path, const torch::Tensor& pred,
                               const torch::Tensor& gt);

}  // namespace neraf::eval
