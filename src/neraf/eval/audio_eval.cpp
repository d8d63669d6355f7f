#include "neraf/eval/audio_eval.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <numeric>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include "neraf/infer/image_output.h"
#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;

namespace neraf::eval {

namespace {

// A metric value for JSON: null when not finite (JSON has no NaN).
nlohmann::json json_number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

double dist3(const geometry::Vec3& a, const geometry::Vec3& b) {
  const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

io::AudioBuffer to_buffer(const std::vector<std::vector<float>>& ch, int rate) {
  io::AudioBuffer b;
  b.sample_rate = rate;
  b.channels = ch;
  return b;
}

io::AudioBuffer tensor_buffer(const torch::Tensor& wave, int rate) {  // [C, L]
  const torch::Tensor w = wave.to(torch::kFloat32).contiguous();
  io::AudioBuffer b;
  b.sample_rate = rate;
  for (int64_t c = 0; c < w.size(0); ++c) {
    const float* p = w[c].data_ptr<float>();
    b.channels.emplace_back(p, p + w.size(1));
  }
  return b;
}

metrics::Variant variant_of(const data::RirSet& rirs) {
  return rirs.layout == data::AudioLayout::raf ? metrics::Variant::raf
                                               : metrics::Variant::soundspaces;
}

// body(n) for n in [0, count), spread over LibTorch's thread count (all cores, or --threads):
// each worker runs LibTorch, BLAS and Griffin-Lim on one thread, so the RIRs, not the small
// matrix products inside one, run in parallel. Every n writes its own result slot, so the result
// does not depend on the thread count. The first exception is rethrown after all workers stop.
void for_each_rir(size_t count, Progress& progress, const std::function<void(size_t)>& body) {
  const size_t workers = std::min<size_t>(std::max(1, torch::get_num_threads()), count);
  std::atomic<size_t> next{0}, done{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex mutex;  // progress and error
  auto work = [&] {
    omp_set_num_threads(1);  // this thread's OpenMP regions (LibTorch's and OpenBLAS's)
    for (size_t n; !failed && (n = next++) < count;) {
      try {
        body(n);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        failed = true;
      }
      std::lock_guard<std::mutex> lock(mutex);
      progress.update(static_cast<int64_t>(++done));
    }
  };
  if (workers <= 1) {
    for (size_t n = 0; n < count; ++n) {
      body(n);
      progress.update(static_cast<int64_t>(n) + 1);
    }
    return;
  }
  std::vector<std::thread> pool;
  for (size_t k = 0; k < workers; ++k) pool.emplace_back(work);
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

std::vector<int64_t> test_indices(const data::RirSet& rirs, int64_t max_rirs) {
  std::vector<int64_t> t = rirs.test;
  if (max_rirs >= 0 && static_cast<int64_t>(t.size()) > max_rirs)
    t.resize(static_cast<size_t>(max_rirs));
  return t;
}

}  // namespace

std::vector<int64_t> nearest_training_rirs(const data::RirSet& train_set,
                                           const std::vector<int64_t>& train, const data::Rir& q,
                                           int64_t k, std::vector<double>* dist) {
  // Tier 0: same heading and source; tier 1: same heading; tier 2: anything. The first
  // non-empty tier is used.
  for (int tier = 0; tier < 3; ++tier) {
    std::vector<std::pair<double, int64_t>> cand;
    for (int64_t i : train) {
      const data::Rir& r = train_set.rirs.at(static_cast<size_t>(i));
      const bool same_heading = r.heading_deg == q.heading_deg;
      const double ds = dist3(r.source, q.source);
      const bool same_source = ds < 1e-3;
      if (tier == 0 && !(same_heading && same_source)) continue;
      if (tier == 1 && !same_heading) continue;
      const double d = dist3(r.mic, q.mic) + (tier == 0 ? 0.0 : ds);
      cand.emplace_back(d, i);
    }
    if (cand.empty()) continue;
    std::stable_sort(cand.begin(), cand.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    if (k > 0 && static_cast<int64_t>(cand.size()) > k) cand.resize(static_cast<size_t>(k));
    std::vector<int64_t> out;
    if (dist) dist->clear();
    for (const auto& [d, i] : cand) {
      out.push_back(i);
      if (dist) dist->push_back(d);
    }
    return out;
  }
  if (dist) dist->clear();
  return {};
}

AudioMethodEval evaluate_audio_model(const infer::AudioField& run, const data::RirSet& rirs,
                                     const std::vector<int64_t>& test, const std::string& label,
                                     const AudioEvalOptions& options,
                                     const std::string& post_processing) {
  const auto t0 = std::chrono::steady_clock::now();
  AudioMethodEval m;
  m.name = label;
  m.post_processing = post_processing;
  m.per_rir.resize(test.size());
  const metrics::Variant variant = variant_of(rirs);
  Progress progress("eval audio (" + label + ")", static_cast<int64_t>(test.size()),
                    ProgressOptions{"RIR", 0.2, 10.0, options.progress});
  for_each_rir(test.size(), progress, [&](size_t n) {
    const int64_t i = test[n];
    const data::Rir& r = rirs.rirs[static_cast<size_t>(i)];
    const torch::Tensor pred = run.predict_log_stft(r.mic, r.source, r.heading_deg);  // [C, F, T]
    const auto wave = infer::griffin_lim_channels(infer::log_stft_to_magnitude(pred), rirs.stft,
                                                  options.seed + static_cast<uint64_t>(n));
    const io::AudioBuffer gt = tensor_buffer(rirs.waveform(i), rirs.sample_rate);
    m.per_rir[n] = metrics::compare_rirs(to_buffer(wave, rirs.sample_rate), gt, variant,
                                         label + " " + r.id, r.id);
    if (!options.out_dir.empty() && static_cast<int64_t>(n) < options.num_images &&
        label == "neraf") {
      char name[64];
      std::snprintf(name, sizeof name, "audio_%05zu.png", n);
      write_stft_comparison_png((fs::path(options.out_dir) / name).string(), pred,
                                rirs.features(i));
    }
  });
  progress.finish();
  m.summary = metrics::summarize(m.per_rir);
  m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return m;
}

AudioEval evaluate_audio(const infer::AudioField& run, const data::RirSet& rirs,
                         const std::vector<int64_t>& train_subset,
                         const AudioEvalOptions& options) {
  require(!rirs.test.empty(), rirs.root + ": the audio test split is empty; nothing to evaluate");
  return evaluate_audio(run, rirs, train_subset, rirs, test_indices(rirs, options.max_rirs),
                        options);
}

AudioEval evaluate_audio(const infer::AudioField& run, const data::RirSet& train_set,
                         const std::vector<int64_t>& train_subset, const data::RirSet& test_set,
                         const std::vector<int64_t>& test, const AudioEvalOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  require(!test.empty(), test_set.root + ": no RIRs to evaluate");
  AudioEval e;
  for (int64_t i : test) e.rir_ids.push_back(test_set.rirs[static_cast<size_t>(i)].id);
  if (!options.out_dir.empty()) fs::create_directories(options.out_dir);
  e.methods.push_back(
      evaluate_audio_model(run, test_set, test, "neraf", options, options.neraf_post_processing));
  if (options.uncalibrated)  // same seeds, same RIRs: only the calibration differs
    e.methods.push_back(evaluate_audio_model(*options.uncalibrated, test_set, test,
                                             kUncalibratedName, options, kGriffinLim));

  if (options.baselines) {
    require(!train_subset.empty(), "baselines: no training RIRs");
    const metrics::Variant variant = variant_of(test_set);
    const auto t_baselines = std::chrono::steady_clock::now();
    AudioMethodEval nearest{"nearest", {}, {}, 0, kMeasuredWaveform},
        linear{"linear", {}, {}, 0, kGriffinLim},
        floor{kGriffinLimFloorName, {}, {}, 0, kGriffinLim};
    for (AudioMethodEval* m : {&nearest, &linear, &floor}) m->per_rir.resize(test.size());
    Progress progress("eval audio (baselines)", static_cast<int64_t>(test.size()),
                      ProgressOptions{"RIR", 0.2, 10.0, options.progress});
    for_each_rir(test.size(), progress, [&](size_t n) {
      const int64_t i = test[n];
      const data::Rir& query = test_set.rirs[static_cast<size_t>(i)];
      const io::AudioBuffer gt = tensor_buffer(test_set.waveform(i), test_set.sample_rate);
      std::vector<double> d;
      const std::vector<int64_t> nb = nearest_training_rirs(train_set, train_subset, query, 4, &d);
      // nearest: the neighbour's measured waveform.
      nearest.per_rir[n] = metrics::compare_rirs(
          tensor_buffer(train_set.waveform(nb[0]), train_set.sample_rate), gt, variant,
          "nearest " + train_set.rirs[static_cast<size_t>(nb[0])].id, query.id);
      // linear: inverse-distance-weighted magnitude blend, then Griffin-Lim.
      std::vector<double> w(nb.size());
      if (d[0] < 1e-6) {
        std::fill(w.begin(), w.end(), 0.0);
        w[0] = 1.0;
      } else {
        for (size_t j = 0; j < nb.size(); ++j) w[j] = 1.0 / (d[j] + 1e-3);
      }
      const double wsum = std::accumulate(w.begin(), w.end(), 0.0);
      torch::Tensor mag;
      for (size_t j = 0; j < nb.size(); ++j) {
        const torch::Tensor mj =
            infer::log_stft_to_magnitude(train_set.features(nb[j])) * (w[j] / wsum);
        mag = mag.defined() ? mag + mj : mj;
      }
      const auto wave = infer::griffin_lim_channels(mag, train_set.stft, options.seed + n);
      linear.per_rir[n] = metrics::compare_rirs(to_buffer(wave, test_set.sample_rate), gt, variant,
                                                "linear", query.id);
      // The floor: the query's own magnitudes, the same Griffin-Lim (same seed as every row).
      const auto own = infer::griffin_lim_channels(
          infer::log_stft_to_magnitude(test_set.features(i)), test_set.stft, options.seed + n);
      floor.per_rir[n] = metrics::compare_rirs(to_buffer(own, test_set.sample_rate), gt, variant,
                                               kGriffinLimFloorName, query.id);
    });
    progress.finish();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_baselines).count();
    for (AudioMethodEval* m : {&nearest, &linear, &floor}) {
      m->summary = metrics::summarize(m->per_rir);
      m->seconds = seconds;
      e.methods.push_back(std::move(*m));
    }
  }
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

nlohmann::json to_json(const metrics::RirErrorSummary& s) {
  nlohmann::json j;
  j["n_rirs"] = s.count;
  const std::pair<const char*, const metrics::MetricStats*> keys[] = {
      {"t60_error_pct", &s.t60_error_pct},
      {"c50_error_db", &s.c50_error_db},
      {"edt_error_s", &s.edt_error_s},
      {"stft_error", &s.stft_error},
      {"invalid_t60", &s.invalid_t60}};
  for (const auto& [k, m] : keys) {
    j[k] = json_number(m->mean);
    j[std::string(k) + "_std"] = json_number(m->std);
    if (m->non_finite > 0) j[std::string(k) + "_non_finite"] = m->non_finite;
  }
  return j;
}

nlohmann::json to_json(const AudioEval& e) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& m : e.methods) {
    j[m.name] = to_json(m.summary);
    j[m.name]["seconds"] = m.seconds;
    j[m.name]["post_processing"] = m.post_processing;
  }
  return j;
}

namespace {

struct PairedMetric {
  const char* key;  // JSON key
  const char* label;
  const char* unit;
  double metrics::RirErrors::*member;
  int digits;
};
constexpr PairedMetric kPairedMetrics[] = {
    {"t60_error_pct", "T60", "%", &metrics::RirErrors::t60_error_pct, 3},
    {"c50_error_db", "C50", "dB", &metrics::RirErrors::c50_error_db, 3},
    {"edt_error_s", "EDT", "s", &metrics::RirErrors::edt_error_s, 5}};

// Calls fn(other, metric, first − other) for each of `others` present in `e`.
template <class Fn>
void for_each_paired(const AudioEval& e, const std::string& first,
                     const std::vector<std::string>& others, Fn fn) {
  const auto find = [&](const std::string& name) -> const AudioMethodEval* {
    for (const auto& m : e.methods)
      if (m.name == name) return &m;
    return nullptr;
  };
  const auto values = [](const AudioMethodEval& m, double metrics::RirErrors::*member) {
    std::vector<double> v;
    for (const auto& r : m.per_rir) v.push_back(r.*member);
    return v;
  };
  const AudioMethodEval* a = find(first);
  if (!a) return;
  for (const std::string& name : others) {
    const AudioMethodEval* b = find(name);
    if (!b) continue;
    for (const PairedMetric& m : kPairedMetrics)
      fn(name, m, metrics::paired_difference(values(*a, m.member), values(*b, m.member)));
  }
}

}  // namespace

nlohmann::json paired_to_json(const AudioEval& e, const std::string& first,
                              const std::vector<std::string>& others) {
  nlohmann::json j = nlohmann::json::object();
  for_each_paired(
      e, first, others,
      [&](const std::string& other, const PairedMetric& m, const metrics::PairedDifference& d) {
        j[other][m.key] = {{"mean_difference", json_number(d.mean)},
                           {"standard_error", json_number(d.standard_error)},
                           {"neraf_better", d.first_better},
                           {"n", d.count}};
      });
  return j;
}

std::string paired_table(const AudioEval& e, const std::string& first,
                         const std::vector<std::string>& others) {
  std::ostringstream out;
  std::string current;
  char buf[200];
  int width = 8;  // the longest name of `others`, so that the columns line up
  for (const std::string& o : others) width = std::max(width, static_cast<int>(o.size()));
  for_each_paired(
      e, first, others,
      [&](const std::string& other, const PairedMetric& m, const metrics::PairedDifference& d) {
        if (current != other) {
          if (current.empty())
            out << first << " − each method below, per RIR (mean ± standard error; RIRs where "
                << first << " is better):";
          current = other;
          std::snprintf(buf, sizeof buf, "\n  %-*s", width, other.c_str());
          out << buf;
        }
        std::snprintf(buf, sizeof buf, "  %s %+.*f ± %.*f %s (%zu/%zu)", m.label, m.digits, d.mean,
                      m.digits, d.standard_error, m.unit, d.first_better, d.count);
        out << buf;
      });
  if (!current.empty()) out << "\n";
  return out.str();
}

namespace {

// "a.b.c" → value for every leaf of `j` (arrays are leaves).
void flatten(const nlohmann::json& j, const std::string& prefix,
             std::map<std::string, nlohmann::json>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      flatten(it.value(), prefix.empty() ? it.key() : prefix + "." + it.key(), out);
  } else {
    out[prefix] = j;
  }
}

// The first key whose values differ, skipping `ignored`; "" when none. The keys that say most
// about a run come first (modality, preset, steps, seed), then shallower keys before deeper ones
// (steps before audio.schedule.max_steps, which follows it), then by name.
std::string first_difference(const nlohmann::json& main, const nlohmann::json& other,
                             const std::set<std::string>& ignored, const std::string& file) {
  std::map<std::string, nlohmann::json> a, b;
  flatten(main, "", a);
  flatten(other, "", b);
  std::set<std::string> unique;
  for (const auto& [k, v] : a) unique.insert(k);
  for (const auto& [k, v] : b) unique.insert(k);
  const std::vector<std::string> first = {"modality", "preset", "steps", "seed"};
  const auto rank = [&](const std::string& k) {
    const auto it = std::find(first.begin(), first.end(), k);
    return std::make_tuple(it - first.begin(), std::count(k.begin(), k.end(), '.'), k);
  };
  std::vector<std::string> keys(unique.begin(), unique.end());
  std::stable_sort(keys.begin(), keys.end(),
                   [&](const std::string& x, const std::string& y) { return rank(x) < rank(y); });
  for (const std::string& k : keys) {
    if (ignored.count(k)) continue;
    const nlohmann::json none = "(unset)";
    nlohmann::json x = a.count(k) ? a[k] : none, y = b.count(k) ? b[k] : none;
    if (k == "audio.vision_run" && x.is_string() && y.is_string()) {  // the same folder
      std::error_code ec;
      x = fs::weakly_canonical(x.get<std::string>(), ec).string();
      y = fs::weakly_canonical(y.get<std::string>(), ec).string();
    }
    if (x != y) return file + " " + k + ": " + y.dump() + " vs " + x.dump();
  }
  return "";
}

}  // namespace

std::vector<std::string> ablation_knobs() {
  return {"audio.grid",
          "audio.grid_features",
          "audio.grid_resolution",
          "audio.relative_geometry",
          "audio.loss",
          "audio.position_max_freq_exp",
          "audio.decay_heads",
          "audio.average_fraction"};
}

std::string training_difference(const nlohmann::json& main_config, const nlohmann::json& main_data,
                                const nlohmann::json& other_config,
                                const nlohmann::json& other_data) {
  std::set<std::string> ignored = {"threads", "save_every", "eval_rays_per_chunk",
                                   "audio.cache_dir"};
  for (const std::string& k : ablation_knobs()) ignored.insert(k);
  std::string d = first_difference(main_config, other_config, ignored, "config.json");
  // "data" and "source" say where the dataset lay, as each training named it (relative or
  // absolute); which data it is is in the file lists, pixel and audio hashes.
  if (d.empty()) d = first_difference(main_data, other_data, {"data", "source"}, "data.json");
  return d;
}

void write_audio_csv(const std::string& path, const AudioEval& e) {
  std::ostringstream out;
  out << "rir_id,method,t60_error_pct,c50_error_db,edt_error_s,stft_error,invalid_t60,"
         "t60_pred_s,t60_gt_s,c50_pred_db,c50_gt_db\n";
  char buf[320];
  for (const auto& m : e.methods)
    for (size_t n = 0; n < m.per_rir.size() && n < e.rir_ids.size(); ++n) {
      const auto& r = m.per_rir[n];
      std::snprintf(buf, sizeof buf, ",%s,%.6g,%.6g,%.6g,%.6g,%d,%.6g,%.6g,%.6g,%.6g\n",
                    m.name.c_str(), r.t60_error_pct, r.c50_error_db, r.edt_error_s, r.stft_error,
                    r.invalid_t60 ? 1 : 0, r.t60_pred_s, r.t60_gt_s, r.c50_pred_db, r.c50_gt_db);
      out << e.rir_ids[n] << buf;
    }
  io::write_text_atomically(path, out.str());
}

std::string audio_table(const std::vector<AudioMethodEval>& methods) {
  std::ostringstream out;
  char buf[200];
  std::snprintf(buf, sizeof buf, "%-28s %10s %10s %10s %10s %9s %6s  %s\n", "method", "T60 (%)",
                "C50 (dB)", "EDT (s)", "STFT err", "invalid", "n", "post-processing");
  out << buf;
  for (const auto& m : methods) {
    const auto& s = m.summary;
    std::snprintf(buf, sizeof buf, "%-28s %10.3f %10.4f %10.5f %10.4f %9.3f %6zu  %s\n",
                  m.name.c_str(), s.t60_error_pct.mean, s.c50_error_db.mean, s.edt_error_s.mean,
                  s.stft_error.mean, s.invalid_t60.mean, s.count, m.post_processing.c_str());
    out << buf;
  }
  return out.str();
}

void write_stft_comparison_png(const std::string& path, const torch::Tensor& pred,
                               const torch::Tensor& gt) {
  TORCH_CHECK(pred.dim() == 3 && gt.dim() == 3, "write_stft_comparison_png: expected [C, F, T]");
  const torch::Tensor p =
      pred[0].to(torch::kFloat32).flip({0}).contiguous();  // [F, T], low at bottom
  const torch::Tensor g = gt[0].to(torch::kFloat32).flip({0}).contiguous();
  const double lo = std::min(p.min().item<double>(), g.min().item<double>());
  const double hi = std::max(p.max().item<double>(), g.max().item<double>());
  const int64_t F = p.size(0), gap = 2, scale = 3;
  auto colour = [&](const torch::Tensor& m) {
    return infer::viridis((m - lo) / std::max(hi - lo, 1e-9));
  };
  // [F, T + gap + Tg, 3] white gap between the two, then each pixel drawn as scale × scale.
  torch::Tensor img = torch::cat({colour(p), torch::ones({F, gap, 3}), colour(g)}, 1)
                          .repeat_interleave(scale, 0)
                          .repeat_interleave(scale, 1);
  infer::write_png(path, img);
}

}  // namespace neraf::eval
