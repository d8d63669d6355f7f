#include "neraf/metrics/rir_errors.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "neraf/dsp/stft.h"
#include "neraf/util/error.h"

namespace neraf::metrics {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string layout(const io::AudioBuffer& a) {
  return std::to_string(a.num_channels()) + " channel(s) at " + std::to_string(a.sample_rate) +
         " Hz";
}

}  // namespace

double t60_error_pct(const std::vector<double>& t60_pred, const std::vector<double>& t60_gt,
                     bool* invalid) {
  require(t60_pred.size() == t60_gt.size() && !t60_gt.empty(),
          "T60 error: prediction and ground truth need the same, nonzero number of channels");
  bool any_invalid = false;
  double sum = 0.0;
  for (size_t c = 0; c < t60_gt.size(); ++c) {
    if (t60_pred[c] < -0.5 || t60_gt[c] < -0.5) any_invalid = true;
    sum += std::abs(t60_pred[c] - t60_gt[c]) / std::abs(t60_gt[c]);
  }
  if (invalid) *invalid = any_invalid;
  const double relative = any_invalid ? 1.0 : sum / double(t60_gt.size());
  return relative * 100.0;
}

int stft_error_frames(size_t gt_length, const dsp::StftParams& params) {
  return std::max(1, static_cast<int>(gt_length / size_t(params.hop_length)));
}

double stft_error(const std::vector<float>& pred, const std::vector<float>& gt,
                  const dsp::StftParams& params, int n_frames) {
  // A centred STFT reflect-pads n_fft/2 samples, which needs a longer signal (torch refuses too).
  if (gt.size() <= size_t(params.n_fft / 2) || pred.size() <= size_t(params.n_fft / 2)) return kNaN;
  const dsp::Matrix lp = dsp::log_magnitude(dsp::stft(pred, params));  // [F, Tp]
  const dsp::Matrix lg = dsp::log_magnitude(dsp::stft(gt, params));    // [F, Tg]
  const int frames = std::min({n_frames, lp.cols, lg.cols});
  double sum = 0.0;
  for (int f = 0; f < lg.rows; ++f) {
    for (int t = 0; t < frames; ++t) sum += std::abs(double(lp(f, t)) - double(lg(f, t)));
  }
  return sum / (double(lg.rows) * double(frames));
}

std::vector<float> fit_to_length(const std::vector<float>& pred, size_t length) {
  std::vector<float> out(pred.begin(), pred.begin() + std::min(pred.size(), length));
  out.resize(length, 0.0f);
  return out;
}

RirErrors compare_rirs(const io::AudioBuffer& pred, const io::AudioBuffer& gt, Variant variant,
                       const std::string& pred_name, const std::string& gt_name) {
  if (pred.num_channels() != gt.num_channels() || pred.sample_rate != gt.sample_rate) {
    throw Error(pred_name + " (" + layout(pred) + ") and " + gt_name + " (" + layout(gt) +
                ") differ: compare a prediction with the ground truth of the same channel count "
                "and sample rate (resample or pick channels first)");
  }
  require(gt.num_channels() > 0, gt_name + ": no audio channels to compare");
  require(gt.sample_rate > 0, gt_name + ": sample rate must be positive");
  require(gt.num_frames() > 0, gt_name + ": empty signal; nothing to compare");
  require_finite_samples(pred, pred_name);
  require_finite_samples(gt, gt_name);

  const double fs = gt.sample_rate;
  const size_t length = static_cast<size_t>(gt.num_frames());
  const dsp::StftParams params = stft_params(variant);
  const int frames = stft_error_frames(length, params);
  const size_t n_ch = gt.channels.size();

  RirErrors e;
  std::vector<double> t60_pred(n_ch), t60_gt(n_ch);
  double c50_sum = 0.0, edt_sum = 0.0, stft_sum = 0.0;
  for (size_t c = 0; c < n_ch; ++c) {
    const std::vector<float> p = fit_to_length(pred.channels[c], length);
    const std::vector<float>& g = gt.channels[c];
    t60_pred[c] = measure_t60(p, fs, variant).reference_t60();
    t60_gt[c] = measure_t60(g, fs, variant).reference_t60();
    edt_sum += std::abs(measure_edt(p, fs).reference_edt() - measure_edt(g, fs).reference_edt());
    const double c50_p = measure_c50(p, fs), c50_g = measure_c50(g, fs);
    c50_sum += std::abs(c50_p - c50_g);
    stft_sum += stft_error(p, g, params, frames);
    e.t60_pred_s += t60_pred[c] / double(n_ch);
    e.t60_gt_s += t60_gt[c] / double(n_ch);
    e.c50_pred_db += c50_p / double(n_ch);
    e.c50_gt_db += c50_g / double(n_ch);
  }

  e.t60_error_pct = t60_error_pct(t60_pred, t60_gt, &e.invalid_t60);
  e.c50_error_db = c50_sum / double(n_ch);
  e.edt_error_s = edt_sum / double(n_ch);
  // Same F and frame count per channel, so the mean of channel means is the mean over [C, F, T].
  e.stft_error = stft_sum / double(n_ch);
  return e;
}

MetricStats mean_and_std(const std::vector<double>& values) {
  MetricStats s;
  const size_t n = values.size();
  if (n == 0) return {kNaN, kNaN, 0};
  double sum = 0.0;
  for (double v : values) {
    sum += v;
    if (!std::isfinite(v)) ++s.non_finite;
  }
  s.mean = sum / double(n);
  if (n < 2) {
    s.std = kNaN;
    return s;
  }
  double sq = 0.0;
  for (double v : values) sq += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(sq / double(n - 1));
  return s;
}

PairedDifference paired_difference(const std::vector<double>& first,
                                   const std::vector<double>& second) {
  require(first.size() == second.size(), "paired_difference: " + std::to_string(first.size()) +
                                             " vs " + std::to_string(second.size()) + " values");
  std::vector<double> d;
  PairedDifference p;
  for (size_t i = 0; i < first.size(); ++i) {
    if (!std::isfinite(first[i]) || !std::isfinite(second[i])) continue;
    d.push_back(first[i] - second[i]);
    if (first[i] < second[i]) ++p.first_better;
  }
  const MetricStats s = mean_and_std(d);
  p.count = d.size();
  p.mean = s.mean;
  p.standard_error = s.std / std::sqrt(double(p.count));
  return p;
}

RirErrorSummary summarize(const std::vector<RirErrors>& errors) {
  RirErrorSummary s;
  s.count = errors.size();
  std::vector<double> t60, c50, edt, stft, invalid;
  for (const RirErrors& e : errors) {
    t60.push_back(e.t60_error_pct);
    c50.push_back(e.c50_error_db);
    edt.push_back(e.edt_error_s);
    stft.push_back(e.stft_error);
    invalid.push_back(e.invalid_t60 ? 1.0 : 0.0);
  }
  s.t60_error_pct = mean_and_std(t60);
  s.c50_error_db = mean_and_std(c50);
  s.edt_error_s = mean_and_std(edt);
  s.stft_error = mean_and_std(stft);
  s.invalid_t60 = mean_and_std(invalid);
  return s;
}

}  // namespace neraf::metrics
