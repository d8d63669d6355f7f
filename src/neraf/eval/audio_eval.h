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
// Metrics per method: mean (and sample std) of t60_error_pct, c50_error_db, edt_error_s,
// stft_error, and invalid_t60 (fraction of RIRs with an invalid T60), n_rirs.
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

struct AudioEvalOptions {
  std::string out_dir;     // per-RIR CSV (audio_per_rir.csv) and PNGs (audio_XXX.png) here
  int64_t num_images = 4;  // predicted | ground-truth log-STFT PNGs for the first N test RIRs
  bool baselines = true;   // also score nearest and linear
  int64_t max_rirs = -1;   // only the first N test RIRs (−1: all)
  uint64_t seed = 0;       // Griffin-Lim initial phases
  bool progress = true;
};

struct AudioMethodEval {
  std::string name;  // "neraf", "nearest", "linear" or an ablation label
  std::vector<metrics::RirErrors> per_rir;
  metrics::RirErrorSummary summary;
  double seconds = 0;  // wall time of the scoring (the two baselines: of both together)
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
// neraf only (for ablation runs): method named `label`.
AudioMethodEval evaluate_audio_model(const infer::AudioField& run, const data::RirSet& rirs,
                                     const std::vector<int64_t>& test, const std::string& label,
                                     const AudioEvalOptions& options);

// {"t60_error_pct", "c50_error_db", "edt_error_s", "stft_error", "invalid_t60", "n_rirs",
//  "<key>_std" ...}
nlohmann::json to_json(const metrics::RirErrorSummary& s);
// {"neraf": {..., "seconds"}, "nearest": {...}, "linear": {...}}
nlohmann::json to_json(const AudioEval& e);
// neraf against each baseline on the same RIRs (metrics::paired_difference of the T60, C50 and
// EDT errors, neraf − baseline): {"nearest": {"t60_error_pct": {"mean_difference",
// "standard_error", "neraf_better", "n"}, ...}, "linear": {...}}; empty without baselines.
nlohmann::json paired_to_json(const AudioEval& e);
// The same as lines to print under the table ("" without baselines).
std::string paired_table(const AudioEval& e);
// Writes "rir_id,method,t60_error_pct,c50_error_db,edt_error_s,stft_error,invalid_t60,
// t60_pred_s,t60_gt_s,c50_pred_db,c50_gt_db" rows (the last four: channel means of the measured
// values, to show a bias).
void write_audio_csv(const std::string& path, const AudioEval& e);
// A fixed-width table of the methods' means.
std::string audio_table(const std::vector<AudioMethodEval>& methods);

// [C, F, T] log-STFTs → one PNG: prediction (left) | ground truth (right), channel 0, low
// frequencies at the bottom, common colour scale (viridis), each pixel 3×3.
void write_stft_comparison_png(const std::string& path, const torch::Tensor& pred,
                               const torch::Tensor& gt);

}  // namespace neraf::eval
