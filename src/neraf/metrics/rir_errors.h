#pragma once
// Errors of a predicted RIR against the ground truth, per RIR and averaged over a test set, with
// the published NeRAF evaluator's semantics (neraf-reference.md §4.1-4.5):
//   t60_error_pct  mean over channels of |T_pred − T_gt| / |T_gt|, ×100; if ANY of the 2C T60
//                  values is invalid (the reference's −1) the RIR scores 100 and counts invalid
//   c50_error_db   mean over channels of |C50_pred − C50_gt|
//   edt_error_s    mean over channels of |EDT_pred − EDT_gt|
//   stft_error     mean |log(|STFT(pred)| + 1e-3) − log(|STFT(gt)| + 1e-3)| (natural log) over
//                  channels × bins × frames. The reference reports it for RAF only; we compute it
//                  for both variants with the variant's STFT parameters.
// Non-finite inputs propagate as in the reference's numpy code: a silent channel has EDT NaN and
// C50 ±inf/NaN, so its RIR's EDT/C50 error is NaN or inf (never a crash); summaries count them.
// Likewise a ground-truth T60 of exactly 0 (the curve drops from above −5 dB to below −5 − decay
// in one sample) gives an infinite (or 0/0 = NaN) relative T60 error, as numpy would.
#include <string>
#include <vector>

#include "neraf/io/audio_file.h"
#include "neraf/metrics/room_acoustics.h"

namespace neraf::metrics {

struct RirErrors {
  double t60_error_pct = 0.0;
  double c50_error_db = 0.0;
  double edt_error_s = 0.0;
  double stft_error = 0.0;
  bool invalid_t60 = false;
  // The measured values behind the errors, averaged over channels (not used by the metrics; they
  // show a bias that absolute errors hide). T60 in seconds (reference rule, −1 when invalid).
  double t60_pred_s = 0.0, t60_gt_s = 0.0;
  double c50_pred_db = 0.0, c50_gt_db = 0.0;
};

// The reference's T60 rule on per-channel values (−1 = invalid, anything < −0.5 counts):
// returns the RIR's T60 error in percent and sets `invalid`. Sizes must match (channels).
double t60_error_pct(const std::vector<double>& t60_pred, const std::vector<double>& t60_gt,
                     bool* invalid);

// Number of STFT frames compared: len(gt) / hop. This is the reference's `max_len` truncation:
// its ground-truth waveforms are max_len·hop samples long (RAF 15360 = 60·256), their centred
// STFT has max_len + 1 frames and the evaluator keeps the first max_len. At least 1.
int stft_error_frames(size_t gt_length, const dsp::StftParams& params);

// L1 distance of log(|STFT| + 1e-3) over the first `n_frames` frames (both signals must give at
// least that many; pass the same length). Single channel: mean over [n_freq, n_frames].
double stft_error(const std::vector<float>& pred, const std::vector<float>& gt,
                  const dsp::StftParams& params, int n_frames);

// The prediction brought to the ground truth's length: zero-padded at the end when shorter (what
// the reference does to its Griffin-Lim output), cut when longer (the reference never has a
// longer prediction; numpy would refuse the negative pad).
std::vector<float> fit_to_length(const std::vector<float>& pred, size_t length);

// All errors of one RIR. pred/gt must have the same channel count and sample rate and finite
// samples, else neraf::Error naming `pred_name` / `gt_name`. pred is fitted to gt's length first.
RirErrors compare_rirs(const io::AudioBuffer& pred, const io::AudioBuffer& gt, Variant variant,
                       const std::string& pred_name = "prediction",
                       const std::string& gt_name = "ground truth");

// Mean and sample standard deviation (N − 1, torch.std_mean's default that ns-eval uses; NaN for
// fewer than two values) of one metric over many RIRs. Non-finite values propagate into the
// plain mean, as in the reference; `non_finite` counts them so callers can warn.
struct MetricStats {
  double mean = 0.0;
  double std = 0.0;
  size_t non_finite = 0;
};

MetricStats mean_and_std(const std::vector<double>& values);

struct RirErrorSummary {
  size_t count = 0;
  MetricStats t60_error_pct;
  MetricStats c50_error_db;
  MetricStats edt_error_s;
  MetricStats stft_error;
  MetricStats invalid_t60;  // mean of 0/1 per RIR = fraction of RIRs with an invalid T60
};

RirErrorSummary summarize(const std::vector<RirErrors>& errors);

// Two methods scored on the same RIRs: the per-RIR differences `first[i] − second[i]` of one
// metric's errors. A difference of two means over a few dozen RIRs is noisy; its standard error
// (sample s.d. of the differences / √n) says whether it stands out of that noise. Pairs with a
// non-finite value are left out (`count` says how many were kept); sizes must match.
struct PairedDifference {
  double mean = 0.0;            // mean of first − second (NaN without pairs)
  double standard_error = 0.0;  // NaN for fewer than two pairs
  size_t first_better = 0;      // pairs where first < second (lower error)
  size_t count = 0;
};

PairedDifference paired_difference(const std::vector<double>& first,
                                   const std::vector<double>& second);

}  // namespace neraf::metrics
