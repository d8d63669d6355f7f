// `neraf eval`: evaluates a trained run on its held-out data and writes one JSON with a key per
// modality ("vision" here; the acoustic branch adds "audio" in evaluate_run_json below).
#include <torch/torch.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/data/image_set.h"
#include "neraf/data/layout.h"
#include "neraf/eval/audio_eval.h"
#include "neraf/eval/evaluation.h"
#include "neraf/geometry/vec.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/exported_model.h"
#include "neraf/infer/run.h"
#include "neraf/io/atomic_file.h"
#include "neraf/io/json_file.h"
#include "neraf/sim/synthesize.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::cli {

namespace {

struct EvalArgs {
  std::string run;
  std::string model;  // an exported MODEL.nrf instead of --run (audio only)
  std::string json;
  std::string images;
  std::string data;
  std::string checkpoint;
  std::string precision = "fp32";  // of the acoustic fields of --run and --ablation-runs
  int64_t max_views = -1;
  int threads = 0;
  bool no_images = false;
  bool quiet = false;
  bool no_baselines = false;
  bool skip_vision = false;
  int64_t max_rirs = -1;
  std::string ablation_runs;  // comma-separated run folders (e.g. trained with --grid none/zeros)
  std::string novel_data;     // another dataset of the same room: every RIR is scored
  // The audio feature cache; unset: what the run's config.json records (the default folder and
  // fp32 for an exported model).
  std::string cache_dir;
  std::string cache_precision;
  CLI::Option* cache_dir_opt = nullptr;
};

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (!s.empty() && start <= s.size()) {
    const size_t end = std::min(s.find(',', start), s.size());
    // "a,,b" or a stray comma is a typo, not "no run": it would silently drop an ablation.
    require(end > start, "--ablation-runs " + s +
                             ": an empty entry; give run folders separated by single commas");
    out.push_back(s.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

// The folder of the PNGs and per-RIR CSVs: written into a temporary folder (`written`) that is
// merged into `shown` (RUN/eval, MODEL_eval or --images) once everything is scored, so a failed
// evaluation leaves the files of the last one as they were (io::write_folder_atomically).
struct OutputDir {
  std::string written, shown;
};

// The RIRs one audio table scores: `test` of `test_set`, baselines from `train_subset` of
// `train_set` (the run's own dataset).
struct AudioEvalSet {
  const data::RirSet& train_set;
  std::vector<int64_t> train_subset;
  const data::RirSet& test_set;
  std::vector<int64_t> test;
};

// The post-processing of a field's predictions (eval::AudioMethodEval::post_processing).
const char* post_processing_of(const infer::AudioRun& run) {
  return run.calibration().defined() ? eval::kCalibratedGriffinLim : eval::kGriffinLim;
}

// An ablation run and its label in the table and JSON (its folder's name).
struct Ablation {
  std::string dir, label;
  infer::AudioRun run;
};

// The run, its baselines and the ablation runs on one set; prints the table under `title`, writes
// the per-RIR CSV into opts.out_dir as `csv_name` → {"neraf", "neraf_uncalibrated", "nearest",
// "linear", "griffin_lim_floor", "paired", "paired_uncalibrated", "ablations",
// "paired_ablations"}.
nlohmann::json score_audio(const infer::AudioField& run, const std::vector<Ablation>& ablations,
                           const AudioEvalSet& set, const eval::AudioEvalOptions& opts,
                           const std::string& csv_name, const std::string& title,
                           const OutputDir& dir) {
  eval::AudioEval e =
      eval::evaluate_audio(run, set.train_set, set.train_subset, set.test_set, set.test, opts);
  nlohmann::json out = eval::to_json(e);
  const nlohmann::json paired = eval::paired_to_json(e);
  if (!paired.empty()) out["paired"] = paired;
  const nlohmann::json paired_uncalibrated = eval::paired_to_json(e, eval::kUncalibratedName);
  if (!paired_uncalibrated.empty()) out["paired_uncalibrated"] = paired_uncalibrated;
  std::vector<std::string> labels;
  if (!ablations.empty()) {
    nlohmann::json abl = nlohmann::json::object();
    eval::AudioEvalOptions o = opts;
    o.num_images = 0;
    for (const Ablation& a : ablations) {
      eval::AudioMethodEval m = eval::evaluate_audio_model(a.run, set.test_set, set.test, a.label,
                                                           o, post_processing_of(a.run));
      abl[a.label] = eval::to_json(m.summary);
      abl[a.label]["run"] = a.dir;
      abl[a.label]["grid"] = a.run.run().config.audio.grid;
      abl[a.label]["grid_features"] = a.run.run().config.audio.grid_features;
      abl[a.label]["grid_resolution"] = a.run.run().config.audio.grid_resolution;
      abl[a.label]["relative_geometry"] = a.run.run().config.audio.relative_geometry;
      abl[a.label]["loss"] = a.run.run().config.audio.loss;
      abl[a.label]["position_max_freq_exp"] = a.run.run().config.audio.position_max_freq_exp;
      abl[a.label]["decay_heads"] = a.run.run().config.audio.decay_heads;
      abl[a.label]["average_fraction"] = a.run.run().config.audio.average_fraction;
      abl[a.label]["post_processing"] = m.post_processing;
      labels.push_back(a.label);
      e.methods.push_back(std::move(m));
    }
    out["ablations"] = abl;
    out["paired_ablations"] = eval::paired_to_json(e, "neraf", labels);
  }
  eval::write_audio_csv((std::filesystem::path(dir.written) / csv_name).string(), e);
  const std::string csv = (std::filesystem::path(dir.shown) / csv_name).string();
  out["per_rir_csv"] = csv;
  std::printf(
      "%s (%s, %zu RIRs, %.1f s; per-RIR CSV %s):\n%s"
      "post-processing: %s = Griffin-Lim of the prediction with the run's energy calibration and "
      "early/late balance, fitted on its training RIRs; %s = Griffin-Lim of the magnitudes as "
      "predicted or blended (%s: the measured magnitudes, what a perfect prediction would score "
      "through it); %s = a training RIR as measured\n%s%s%s",
      title.c_str(), data::to_string(set.test_set.layout), e.rir_ids.size(), e.seconds, csv.c_str(),
      eval::audio_table(e.methods).c_str(), eval::kCalibratedGriffinLim, eval::kGriffinLim,
      eval::kGriffinLimFloorName, eval::kMeasuredWaveform, eval::paired_table(e).c_str(),
      eval::paired_table(e, eval::kUncalibratedName).c_str(),
      eval::paired_table(e, "neraf", labels).c_str());
  return out;
}

// The cache settings eval reads the RIR features with: the flags, else the run's.
struct CacheChoice {
  std::string dir;
  std::string precision = "fp32";
  int64_t max_len = 0;  // the run's --max-len (0: automatic, as training resolved it)
};

data::RirSet load_rirs(const std::string& dir, bool progress, const CacheChoice& cache,
                       int64_t max_len) {
  data::RirLoadOptions load;
  load.progress = progress;
  load.cache_dir = cache.dir;
  load.half_precision = data::parse_cache_precision(cache.precision);
  load.max_len = max_len;
  return data::load_rir_set(dir, load);
}

// --novel-data must be the run's room heard at other positions. Simulated sets record their room
// (scene.json) and the scale their RIRs were written at (synth_info.json); another scale would
// bias the STFT error (the other metrics are scale-free).
void check_same_room(const std::string& run_data_dir, const std::string& novel_dir) {
  if (const std::optional<std::string> differs = sim::room_difference(run_data_dir, novel_dir))
    throw Error(novel_dir + ": is another room than the run's data " + run_data_dir + " (" +
                *differs +
                " differs in scene.json); --novel-data takes the run's room heard at other "
                "microphone positions");
  const std::optional<double> expected = sim::synthesized_gain(run_data_dir),
                              got = sim::synthesized_gain(novel_dir);
  if (!expected || !got) return;
  require(std::abs(*expected - *got) <= 1e-9 * std::max(*expected, *got),
          novel_dir + ": its RIRs were synthesised at gain " + std::to_string(*got) +
              ", the run's data at " + std::to_string(*expected) +
              "; re-synthesise it with `neraf synth ... --gain-from " + run_data_dir + "`");
}

// What scoring needs of the field beside its predictions: the run's data manifest, seed, audio
// fraction and grid mode (from the run folder, or as an exported model recorded them).
struct EvalField {
  const infer::AudioField& field;
  nlohmann::json manifest;  // RUN/data.json
  uint64_t seed = 0;
  double audio_fraction = 1;
  std::string grid;
  CacheChoice cache;  // the run's feature cache (before the flags)
  // What the field's predictions carry (eval::kCalibratedGriffinLim or kGriffinLim) and, for a
  // calibrated run, the same field loaded without its calibration (else nullptr).
  std::string post_processing = eval::kGriffinLim;
  const infer::AudioField* uncalibrated = nullptr;
  // --run only (nullptr for --model): the run, which the ablation runs must have trained like.
  const infer::AudioRun* run = nullptr;
  // A multi-scene run: the scene scored (the ablation runs are loaded at the same scene); −1 else.
  int64_t scene = -1;
};

// What eval scores of a trained run (scene: −1, or a multi-scene run's scene).
EvalField eval_field_of_run(const infer::AudioRun& run, const infer::AudioRun* uncalibrated,
                            int64_t scene = -1) {
  const infer::AudioConfig& a = run.run().config.audio;
  return {run,
          run.run().manifest,
          run.run().config.seed,
          a.fraction,
          a.grid,
          {a.cache_dir, a.cache_precision, a.max_len},
          post_processing_of(run),
          uncalibrated,
          &run,
          scene};
}

// One row of the printed summary: "  name  T60 … C50 … EDT … STFT …".
void print_metrics_row(const std::string& name, const nlohmann::json& v) {
  auto num = [&v](const char* key) { return v[key].is_number() ? v[key].get<double>() : NAN; };
  std::printf("  %-20s T60 %8.3f %%  C50 %7.3f dB  EDT %8.5f s  STFT %7.4f\n", name.c_str(),
              num("t60_error_pct"), num("c50_error_db"), num("edt_error_s"), num("stft_error"));
}

// Refuses an ablation run whose training differs from the main run's in anything but the
// ablation knobs (eval::training_difference), whose checkpoint is at another step, or which
// lacks the calibration the main run has: its numbers would not measure the ablated option.
void check_trained_alike(const infer::AudioRun& main, const std::string& main_dir,
                         const infer::AudioRun& other, const std::string& dir) {
  std::string knobs;
  for (const std::string& k : eval::ablation_knobs()) knobs += (knobs.empty() ? "" : ", ") + k;
  const std::string difference =
      eval::training_difference(infer::to_json(main.run().config), main.run().manifest,
                                infer::to_json(other.run().config), other.run().manifest);
  require(difference.empty(), "--ablation-runs: " + dir + " was not trained like --run " +
                                  main_dir + " (" + difference +
                                  "); an ablation may differ only in " + knobs +
                                  ": retrain it with --run's settings and only the ablated flag");
  require(other.step() == main.step(),
          "--ablation-runs: " + dir + " is at step " + std::to_string(other.step()) + ", --run " +
              main_dir + " at step " + std::to_string(main.step()) +
              "; finish its training (neraf train --out " + dir +
              " --resume) or pick --run's --checkpoint at the same step");
  // Both have the same audio.energy_calibration (compared above); one may not be calibrated yet.
  const bool main_calibrated = main.calibration().defined();
  require(other.calibration().defined() == main_calibrated,
          "--ablation-runs: " + (main_calibrated ? dir : "--run " + main_dir) +
              " has no calibration for its checkpoint and " +
              (main_calibrated ? "--run " + main_dir : dir) + " has; run: neraf calibrate --run " +
              (main_calibrated ? dir : main_dir));
}

// --data, else the dataset the run (or the model) records, which must still be there.
std::string dataset_of(const nlohmann::json& manifest, const EvalArgs& args) {
  if (!args.data.empty()) return args.data;
  require(manifest.contains("data") && manifest["data"].is_string(),
          "the run's data.json records no dataset path (\"data\"); pass --data DIR");
  const std::string dir = manifest["data"].get<std::string>();
  std::error_code ec;
  require(std::filesystem::is_directory(dir, ec),
          dir +
              ": the dataset recorded in the run's data.json (or the model) is gone; restore it, "
              "or pass --data DIR holding the same data");
  return dir;
}

// The acoustic field on the test RIRs (and, with --novel-data, on every RIR of another dataset of
// the same room), with the nearest/linear baselines and the ablation runs.
nlohmann::json evaluate_audio_json(const EvalField& source, const EvalArgs& args,
                                   const OutputDir& dir) {
  const infer::AudioField& run = source.field;
  const std::string data_dir = dataset_of(source.manifest, args);
  CacheChoice cache = source.cache;
  if (args.cache_dir_opt && args.cache_dir_opt->count()) cache.dir = args.cache_dir;
  if (!args.cache_precision.empty()) cache.precision = args.cache_precision;
  // The run's data as training loaded it (same options, same cache file).
  data::RirSet rirs = load_rirs(data_dir, !args.quiet, cache, cache.max_len);
  infer::check_audio_manifest(source.manifest.at("audio"), rirs, data_dir);
  std::vector<Ablation> ablations;
  std::set<std::string> labels;  // the table's and the JSON's name of each: its folder's name
  require(args.ablation_runs.empty() || source.run,
          "--ablation-runs: needs --run (an exported --model does not record how it was trained, "
          "so the ablations cannot be checked against it)");
  for (const std::string& dir : split_commas(args.ablation_runs)) {
    std::error_code ec;
    require(!std::filesystem::equivalent(dir, args.run, ec),
            "--ablation-runs " + dir +
                ": is --run itself; give runs trained with one setting "
                "changed (e.g. --grid zeros)");
    const std::string label = std::filesystem::path(dir).lexically_normal().filename().string();
    require(labels.insert(label).second && label != "neraf" && label != eval::kUncalibratedName &&
                label != "nearest" && label != "linear" && label != eval::kGriffinLimFloorName,
            "--ablation-runs: two runs (or a run and a method) are called '" + label +
                "' (each is labelled by its folder's name); give each its own folder name");
    ablations.push_back(
        {dir, label,
         infer::load_audio_run(dir, torch::kCPU, "", nerf::parse_precision(args.precision),
                               /*calibrated=*/true, source.scene)});
    infer::check_audio_manifest(ablations.back().run.run().manifest.at("audio"), rirs,
                                dir + "/data.json");
    check_trained_alike(*source.run, args.run, ablations.back().run, dir);
  }
  // A multi-scene run's scene is scored at its own frames (training padded it to the longest's).
  if (run.info().max_len < rirs.max_len) rirs = data::first_frames(rirs, run.info().max_len);
  eval::AudioEvalOptions opts;
  opts.progress = !args.quiet;
  opts.baselines = !args.no_baselines;
  opts.seed = source.seed;
  opts.neraf_post_processing = source.post_processing;
  opts.uncalibrated = source.uncalibrated;
  opts.out_dir = dir.written;
  if (args.no_images) opts.num_images = 0;
  const std::vector<int64_t> subset =
      infer::audio_train_subset(rirs, source.audio_fraction, source.seed);

  require(!rirs.test.empty(), data_dir + ": the audio test split is empty; nothing to evaluate");
  // Checked before anything is scored or written.
  std::optional<data::RirSet> novel;
  if (!args.novel_data.empty()) {
    // Refused before its features are computed (no cache is left in a set that is refused).
    const data::DatasetLayout layout = data::detect_layout(args.novel_data);
    const bool same_layout =
        rirs.layout == data::AudioLayout::soundspaces ? layout.soundspaces : layout.raf;
    require(same_layout, args.novel_data + ": is not a " + data::to_string(rirs.layout) +
                             " dataset as the run's is; synthesise or convert it in the run's "
                             "format");
    check_same_room(data_dir, args.novel_data);
    // Cut or padded to the run's frames, whatever the set's own automatic value would be.
    novel = load_rirs(args.novel_data, !args.quiet, cache, rirs.max_len);
    infer::check_same_room_format(source.manifest.at("audio"), *novel, args.novel_data);
    // Positions within 1 mm of a training microphone's are not new positions.
    int64_t seen = 0;
    for (const data::Rir& r : novel->rirs)
      for (int64_t i : subset)
        if (geometry::norm(r.mic - rirs.rirs[static_cast<size_t>(i)].mic) < 1e-3) {
          ++seen;
          break;
        }
    if (seen > 0)
      warn("--novel-data " + args.novel_data + ": " + std::to_string(seen) + " of " +
           std::to_string(novel->size()) +
           " RIRs are at microphone positions the run trained on; their scores are not of new "
           "positions");
  }
  auto first_rirs = [&](std::vector<int64_t> rirs_to_score) {  // --max-rirs
    if (args.max_rirs >= 0 && static_cast<int64_t>(rirs_to_score.size()) > args.max_rirs)
      rirs_to_score.resize(static_cast<size_t>(args.max_rirs));
    return rirs_to_score;
  };
  nlohmann::json out = score_audio(run, ablations, {rirs, subset, rirs, first_rirs(rirs.test)},
                                   opts, "audio_per_rir.csv", "audio, held-out test split", dir);
  out["grid"] = source.grid;
  if (novel) {
    std::vector<int64_t> all(novel->rirs.size());
    std::iota(all.begin(), all.end(), int64_t{0});
    opts.num_images = 0;
    out["novel"] = score_audio(run, ablations, {rirs, subset, *novel, first_rirs(all)}, opts,
                               "audio_novel_per_rir.csv",
                               "audio at new microphone positions (" + args.novel_data + ")", dir);
    out["novel"]["data"] = args.novel_data;
  }
  return out;
}

// The mean over scenes (each scene counts once, as the paper's table averages its rooms) of
// every method's metrics and of every paired difference; n_rirs is the total.
nlohmann::json mean_over_scenes(const std::vector<nlohmann::json>& scenes) {
  nlohmann::json mean = nlohmann::json::object();
  const double n = static_cast<double>(scenes.size());
  auto average = [&](auto&& get) {  // get(scene) → the json number or null
    double sum = 0;
    for (const nlohmann::json& s : scenes) {
      const nlohmann::json v = get(s);
      if (!v.is_number()) return nlohmann::json();
      sum += v.get<double>();
    }
    return nlohmann::json(sum / n);
  };
  const char* metrics[] = {"t60_error_pct", "c50_error_db", "edt_error_s", "stft_error",
                           "invalid_t60"};
  std::vector<std::pair<std::string, std::string>> methods;  // (group, method); group "" = top
  for (const auto& [k, v] : scenes.front().items())
    if (v.is_object() && v.contains("t60_error_pct")) methods.push_back({"", k});
  if (scenes.front().contains("ablations"))
    for (const auto& [k, v] : scenes.front()["ablations"].items())
      methods.push_back({"ablations", k});
  for (const auto& [group, name] : methods) {
    nlohmann::json m;
    int64_t count = 0;
    for (const nlohmann::json& s : scenes) {
      const nlohmann::json& x = group.empty() ? s : s[group];
      count += x.contains(name) ? x[name].value("n_rirs", int64_t{0}) : 0;
    }
    m["n_rirs"] = count;
    for (const char* key : metrics)
      m[key] = average([&](const nlohmann::json& s) {
        const nlohmann::json& x = group.empty() ? s : s[group];
        return x.contains(name) ? x[name].value(key, nlohmann::json()) : nlohmann::json();
      });
    (group.empty() ? mean[name] : mean[group][name]) = m;
  }
  // Paired differences: the mean of the per-scene means; its standard error from the scenes'
  // (independent sets of RIRs): sqrt(Σ se²)/N.
  for (const char* group : {"paired", "paired_uncalibrated", "paired_ablations"}) {
    if (!scenes.front().contains(group)) continue;
    for (const auto& [other, per_metric] : scenes.front()[group].items())
      for (const auto& [key, unused] : per_metric.items()) {
        double sum = 0, var = 0;
        int64_t count = 0;
        bool ok = true;
        for (const nlohmann::json& s : scenes) {
          const nlohmann::json d =
              s.contains(group) && s[group].contains(other) && s[group][other].contains(key)
                  ? s[group][other][key]
                  : nlohmann::json();
          if (!d.is_object() || !d["mean_difference"].is_number() ||
              !d["standard_error"].is_number()) {
            ok = false;
            break;
          }
          sum += d["mean_difference"].get<double>();
          var += std::pow(d["standard_error"].get<double>(), 2);
          count += d.value("n", int64_t{0});
        }
        if (!ok) continue;
        mean[group][other][key] = {
            {"mean_difference", sum / n}, {"standard_error", std::sqrt(var) / n}, {"n", count}};
      }
  }
  return mean;
}

nlohmann::json evaluate_vision_json(infer::LoadedRun& run, const EvalArgs& args,
                                    const OutputDir& dir) {
  const std::string data_dir = dataset_of(run.manifest, args);
  data::ImageLoadOptions load;
  load.progress = !args.quiet;
  const data::ImageSet images = data::load_transforms_json(data_dir, load);
  // The eval cameras must be the ones the run was trained against (same normalisation).
  const nlohmann::json now = infer::make_data_manifest(images, data_dir);
  // The held-out pictures and cameras too (runs from before the pixel hash have none).
  for (const char* key :
       {"num_train", "eval_files", "world_scale", "eval_intrinsics", "eval_pixels_fnv1a"}) {
    if (!run.manifest.contains(key)) continue;
    require(now[key] == run.manifest[key],
            data_dir + ": differs from the dataset the run was trained on (" + key +
                "); pass the original dataset with --data");
  }
  eval::VisionEvalOptions opts;
  opts.chunk = run.config.eval_rays_per_chunk;
  opts.max_views = args.max_views;
  opts.progress = !args.quiet;
  if (!args.no_images) opts.image_dir = dir.written;
  const eval::VisionEval e = eval::evaluate_vision(run.model, images.eval, opts);
  const std::string images_line =
      opts.image_dir.empty() ? "" : "; GT|prediction images in " + dir.shown;
  std::printf("vision: PSNR %.3f dB  SSIM %.4f  over %lld eval views (%.1f s)%s\n", e.psnr, e.ssim,
              static_cast<long long>(e.n_views), e.seconds, images_line.c_str());
  return eval::to_json(e);
}

}  // namespace

void register_eval(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Evaluate a trained run on its held-out views (PSNR, SSIM) and RIRs (T60, C50, EDT, STFT "
      "error against the baselines), or an exported model on the RIRs, and write JSON");
  cmd->footer(
      "PSNR and SSIM follow nerfstudio's evaluation (torchmetrics semantics, mean over the\n"
      "eval views). The JSON has {\"run\", \"checkpoint\", \"step\", \"vision\": {\"psnr\",\n"
      "\"ssim\", \"n_views\", \"views\": [...]}, \"audio\": {\"neraf\"|\"neraf_uncalibrated\"|\n"
      "\"nearest\"|\"linear\"|\"griffin_lim_floor\": {\"t60_error_pct\", \"c50_error_db\",\n"
      "\"edt_error_s\", \"stft_error\", \"invalid_t60\", \"n_rirs\", \"*_std\",\n"
      "\"post_processing\"}, \"paired\", "
      "\"paired_uncalibrated\", \"ablations\", \"paired_ablations\", \"novel\"}}. Audio follows\n"
      "NeRAF's evaluator: predicted log-STFT → Griffin-Lim (32 it., seeded) → T60/C50/EDT vs\n"
      "the measured waveform. A calibrated run (the cpu preset) is scored twice: \"neraf\" with\n"
      "the energy calibration and early/late balance fitted on its training RIRs, and\n"
      "\"neraf_uncalibrated\" without, as the linear baseline is rendered (each row states its\n"
      "post-processing). --ablation-runs must have trained exactly as --run but for audio.grid,\n"
      "audio.grid_features, audio.grid_resolution, audio.relative_geometry, audio.loss,\n"
      "audio.position_max_freq_exp, audio.decay_heads or audio.average_fraction (same\n"
      "modality, preset, steps, seed, data; else refused).\n"
      "Baselines:\n"
      "nearest = the measured RIR of the closest training mic with the same heading and source;\n"
      "linear = inverse-distance blend of the 2-4 closest such training RIRs' magnitudes +\n"
      "Griffin-Lim. griffin_lim_floor is not a method: the test RIR's own measured magnitudes\n"
      "through the same Griffin-Lim, the error a perfect prediction would still have.\n"
      "Side-by-side GT | prediction PNGs (images: eval_*.png; audio: audio_*.png\n"
      "prediction | GT log-STFT) and audio_per_rir.csv go to RUN/eval/ (or --images DIR).\n"
      "The test split holds out (source, heading) pairs at trained microphone positions;\n"
      "--novel-data scores new positions too (audio.novel).\n"
      "A multi-scene run (neraf train with several --data) is scored scene by scene on each\n"
      "scene's test split (audio.scenes.NAME; PNGs and CSVs in RUN/eval/NAME/) and as the mean\n"
      "over scenes, each counting once (audio.mean); --ablation-runs must be multi-scene runs\n"
      "of the same scenes.\n"
      "With --model (neraf export) only the audio is scored; PNGs and CSVs go to\n"
      "MODEL_eval/ (or --images DIR).\n"
      "Example: neraf eval --run runs/demo --json runs/demo/eval.json");
  CLI::Option* run_opt = cmd->add_option("--run", args->run, "Run folder made by neraf train");
  CLI::Option* model_opt = cmd->add_option(
      "--model", args->model,
      "Exported model made by neraf export, instead of --run: its acoustic field is scored "
      "(audio only) with the run's dataset, seed and training subset recorded in the file");
  run_opt->excludes(model_opt);
  cmd->add_option("--json", args->json, "Output JSON file")->required();
  cmd->add_option("--images", args->images, "Folder for the GT|prediction PNGs (default RUN/eval)");
  cmd->add_flag("--no-images", args->no_images, "Do not write the comparison PNGs");
  cmd->add_option("--data", args->data,
                  "Dataset folder (default: the one recorded in RUN/data.json)");
  cmd->add_option("--checkpoint", args->checkpoint,
                  "A specific checkpoint file (default: the run's latest)")
      ->needs(run_opt);
  cmd->add_option("--precision", args->precision,
                  "Audio: arithmetic of the acoustic fields of --run and --ablation-runs: fp32 "
                  "(default, whatever trained them) or bf16 (as a bf16 run trained)")
      ->check(CLI::IsMember({"fp32", "bf16"}))
      ->needs(run_opt);
  cmd->add_option("--max-views", args->max_views,
                  "Vision: evaluate only the first N eval views (not with --model: an exported "
                  "model has no radiance field)")
      ->transform(whole_number(1, 10000000))
      ->excludes(model_opt);
  cmd->add_option("--threads", args->threads,
                  "CPU threads (default: all cores; at most 4 x the cores)")
      ->transform(thread_count());
  cmd->add_flag("--quiet", args->quiet, "No progress bar");
  cmd->add_flag("--skip-vision", args->skip_vision, "Do not evaluate the images (audio only)");
  cmd->add_flag("--no-baselines", args->no_baselines,
                "Audio: do not score the nearest-neighbour and linear-interpolation baselines "
                "(nor the Griffin-Lim floor)");
  cmd->add_option("--max-rirs", args->max_rirs, "Audio: evaluate only the first N test RIRs")
      ->transform(whole_number(1, 100000000));
  args->cache_dir_opt = cmd->add_option(
      "--cache-dir", args->cache_dir,
      "Audio: folder of the RIR feature cache (default: the one the run was trained with, "
      "recorded in RUN/config.json; else DATA/.neraf_cache)");
  cmd->add_option("--cache-precision", args->cache_precision,
                  "Audio: feature cache values, fp32 or fp16 (default: the run's, recorded in "
                  "RUN/config.json; fp32 with --model)")
      ->check(CLI::IsMember({"fp32", "fp16"}));
  cmd->add_option("--ablation-runs", args->ablation_runs,
                  "Audio: comma-separated run folders trained exactly as --run but for the "
                  "ablated option (--grid, --grid-features, --grid-resolution, --audio-loss, "
                  "--no-relative-geometry, --position-max-freq-exp, --decay-heads, "
                  "--audio-average; same modality, preset, steps, seed and data, else refused), "
                  "scored on the same test RIRs and added to the table and JSON "
                  "(audio.ablations, labelled by folder name, and audio.paired_ablations: --run "
                  "− each)");
  cmd->add_option("--novel-data", args->novel_data,
                  "Audio: another dataset of the same room (same layout and rates, e.g. "
                  "`neraf synth --preset demo --mics random`): every RIR of it is scored as well, "
                  "at microphone positions the run never saw (JSON audio.novel, "
                  "audio_novel_per_rir.csv); the baselines still use the run's training RIRs");
  cmd->callback([args]() {
    if (args->threads > 0) torch::set_num_threads(args->threads);
    if (args->run.empty() && args->model.empty()) throw CLI::RequiredError("--run or --model");
    const std::vector<FlagPath> inputs = {
        {"--model", args->model}, {"--data", args->data}, {"--novel-data", args->novel_data}};
    require_safe_output({"--json", args->json}, inputs, args->run);
    require_extension({"--json", args->json}, ".json");
    split_commas(args->ablation_runs);  // a typo in the list fails now, not after the scoring
    if (!args->novel_data.empty() && !args->run.empty()) {
      std::vector<std::string> own = infer::run_input_folders(args->run);
      if (!args->data.empty()) own.push_back(args->data);
      for (const std::string& folder : own) {
        std::error_code ec;
        require(!std::filesystem::equivalent(folder, args->novel_data, ec),
                "--novel-data " + args->novel_data +
                    ": is the run's own dataset, whose RIRs it trained on; give a dataset of the "
                    "same room at other microphone positions (neraf synth --mics random --seed N)");
      }
    }
    std::vector<FlagPath> folder_inputs = inputs;
    folder_inputs.push_back({"--json", args->json});
    require_safe_output_folder({"--images", args->images}, folder_inputs, args->run);
    require_cache_folder({"--cache-dir", args->cache_dir}, args->run);
    // The PNGs and per-RIR CSVs: --images, else RUN/eval or MODEL_eval beside the model.
    const std::string shown =
        !args->images.empty() ? args->images
        : args->run.empty()
            ? std::filesystem::path(args->model).replace_extension("").string() + "_eval"
            : (std::filesystem::path(args->run) / "eval").string();
    if (args->images.empty()) {
      std::string beside = std::filesystem::path(shown).parent_path().string();
      if (beside.empty()) beside = ".";
      const bool writable = ::access(beside.c_str(), W_OK) == 0;
      const int why = errno;  // before the message is built
      std::error_code ec;
      const std::string fix =
          "eval writes its comparison PNGs and per-RIR CSVs there by default: pass --images DIR, "
          "a writable folder for them";
      require(writable, beside + ": not writable (" + std::strerror(why) + "); " + fix);
      require(!std::filesystem::exists(shown, ec) || std::filesystem::is_directory(shown, ec),
              shown + ": exists and is not a folder; " + fix);
    }
    if (!args->model.empty()) {
      const infer::ExportedModel model = infer::load_exported_model(args->model);
      const nlohmann::json& meta = model.metadata();
      require(meta.contains("data") && meta["data"].contains("audio"),
              args->model + ": records no training data manifest; re-export it with neraf export");
      // The file holds its calibration folded in: scored as exported (no uncalibrated row).
      EvalField source{
          model,
          meta["data"],
          meta.value("seed", uint64_t{0}),
          meta.value("audio_fraction", 1.0),
          meta.value("grid", std::string("sampled")),
          {},
          meta.value("calibration", false) ? eval::kCalibratedGriffinLim : eval::kGriffinLim};
      // Frames per RIR as training loaded them, when they were set (--max-len, or a multi-scene
      // run's common value) rather than automatic.
      const nlohmann::json& audio = meta["data"]["audio"];
      if (audio.value("max_len_source", std::string()) == "--max-len")
        source.cache.max_len = audio.value("max_len", int64_t{0});
      nlohmann::json out = {{"model", args->model},
                            {"run", meta.value("run", std::string())},
                            {"checkpoint", meta.value("checkpoint", std::string())},
                            {"step", meta.value("step", int64_t{0})}};
      io::write_folder_atomically(
          shown,
          [&](const std::string& tmp) {
            out["audio"] = evaluate_audio_json(source, *args, {tmp, shown});
          },
          io::FolderWrite::merge);
      io::write_json_atomically(args->json, out);
      return;
    }
    const std::string config_path = infer::run_config_file(args->run);
    const infer::TrainConfig cfg = infer::read_run_config(config_path);
    nlohmann::json out = {{"run", args->run}};
    io::write_folder_atomically(
        shown,
        [&](const std::string& tmp) {
          const OutputDir dir{tmp, shown};
          if (!cfg.audio.vision_runs.empty()) {
            // Multi-scene: every scene scored on its own test split (its PNGs and CSVs in a
            // folder named after it), then the mean over scenes.
            require(args->data.empty(),
                    "--data: a multi-scene run records each scene's dataset; drop --data");
            require(args->novel_data.empty(),
                    "--novel-data: not available for a multi-scene run (it names one room); "
                    "export or render one --scene instead");
            const nlohmann::json manifest =
                io::read_json((std::filesystem::path(args->run) / "data.json").string());
            const std::vector<std::string> names = infer::scene_names(manifest);
            require(names.size() == cfg.audio.vision_runs.size(),
                    args->run + "/data.json: does not list the run's scenes; re-run neraf train");
            nlohmann::json audio = {{"scenes", nlohmann::json::object()}, {"scene_order", names}};
            std::vector<nlohmann::json> per_scene;
            for (size_t k = 0; k < names.size(); ++k) {
              const int64_t scene = static_cast<int64_t>(k);
              const infer::AudioRun run =
                  infer::load_audio_run(args->run, torch::kCPU, args->checkpoint,
                                        nerf::parse_precision(args->precision), true, scene);
              std::optional<infer::AudioRun> uncalibrated;
              if (run.calibration().defined())
                uncalibrated =
                    infer::load_audio_run(args->run, torch::kCPU, args->checkpoint,
                                          nerf::parse_precision(args->precision), false, scene);
              const EvalField source =
                  eval_field_of_run(run, uncalibrated ? &*uncalibrated : nullptr, scene);
              const OutputDir sub{(std::filesystem::path(tmp) / names[k]).string(),
                                  (std::filesystem::path(shown) / names[k]).string()};
              std::filesystem::create_directories(sub.written);
              std::printf("scene %zu/%zu: %s (%s)\n", k + 1, names.size(), names[k].c_str(),
                          run.run().manifest.value("data", std::string("?")).c_str());
              per_scene.push_back(evaluate_audio_json(source, *args, sub));
              per_scene.back()["data"] = run.run().manifest.value("data", std::string());
              audio["scenes"][names[k]] = per_scene.back();
              out["checkpoint"] = run.run().checkpoint;
              out["step"] = run.step();
            }
            audio["mean"] = mean_over_scenes(per_scene);
            out["precision"] = args->precision;
            out["audio"] = audio;
            const nlohmann::json& m = audio["mean"];
            std::printf("mean over %zu scenes (each scene counts once):\n", names.size());
            for (const auto& [name, v] : m.items())
              if (v.contains("t60_error_pct")) print_metrics_row(name, v);
            if (m.contains("ablations"))
              for (const auto& [name, v] : m["ablations"].items()) print_metrics_row(name, v);
            if (!args->skip_vision)
              std::printf(
                  "vision: not scored for a multi-scene acoustic run (it has no radiance "
                  "field of its own); eval each scene's --vision-run\n");
            return;
          }
          require(cfg.modality != infer::Modality::vision || !args->skip_vision,
                  args->run +
                      ": a vision-only run has no acoustic field, so --skip-vision leaves "
                      "nothing to evaluate; drop --skip-vision");
          if (cfg.modality != infer::Modality::vision) {
            const infer::AudioRun audio = infer::load_audio_run(
                args->run, torch::kCPU, args->checkpoint, nerf::parse_precision(args->precision));
            out["checkpoint"] = audio.run().checkpoint;
            out["step"] = audio.step();
            out["precision"] = args->precision;
            // A calibrated run is also scored without its calibration (the linear baseline
            // renders through the same Griffin-Lim with none).
            std::optional<infer::AudioRun> uncalibrated;
            if (audio.calibration().defined())
              uncalibrated = infer::load_audio_run(args->run, torch::kCPU, args->checkpoint,
                                                   nerf::parse_precision(args->precision),
                                                   /*calibrated=*/false);
            const EvalField source =
                eval_field_of_run(audio, uncalibrated ? &*uncalibrated : nullptr);
            out["audio"] = evaluate_audio_json(source, *args, dir);
          }
          if (!args->skip_vision) {
            // An audio-only run has no radiance field of its own: its --vision-run's is evaluated.
            const bool own = cfg.modality != infer::Modality::audio;
            std::error_code ec;
            require(own || std::filesystem::is_directory(cfg.audio.vision_run, ec),
                    config_path + ": audio.vision_run " + cfg.audio.vision_run +
                        " (whose radiance field the images are scored with) is gone; restore "
                        "it, or pass --skip-vision to score the audio only");
            infer::LoadedRun run = infer::load_run(own ? args->run : cfg.audio.vision_run,
                                                   torch::kCPU, own ? args->checkpoint : "");
            if (!out.contains("checkpoint")) {
              out["checkpoint"] = run.checkpoint;
              out["step"] = run.step;
            }
            out["vision"] = evaluate_vision_json(run, *args, dir);
            if (!own) out["vision"]["run"] = cfg.audio.vision_run;
          }
        },
        io::FolderWrite::merge);
    io::write_json_atomically(args->json, out);
  });
}

}  // namespace neraf::cli
