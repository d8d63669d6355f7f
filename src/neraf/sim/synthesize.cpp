#include "neraf/sim/synthesize.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <numeric>
#include <set>

#include "neraf/io/atomic_file.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/io/png.h"
#include "neraf/sim/hrtf.h"
#include "neraf/sim/image_renderer.h"
#include "neraf/sim/layout_writers.h"
#include "neraf/sim/microphones.h"
#include "neraf/sim/plan_drawing.h"
#include "neraf/sim/rir_simulator.h"
#include "neraf/sim/scene_json.h"
#include "neraf/sim/seeded_random.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"
#include "neraf/util/log.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;

namespace neraf::sim {

using nlohmann::json;

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The folder itself is built in a temporary folder and renamed into place (synthesize).
void check_out_dir(const std::string& dir, bool force) {
  require(!dir.empty(), "--out: no output folder given; pass --out DIR");
  std::error_code ec;
  if (fs::exists(dir, ec)) {
    require(fs::is_directory(dir, ec), dir + ": exists and is not a folder; choose another --out");
    const bool empty = fs::directory_iterator(dir, ec) == fs::directory_iterator();
    require(empty || force,
            dir +
                ": the folder is not empty; choose a new or empty --out folder, or pass "
                "--force to replace it");
    // --force replaces a dataset synth wrote; it must not delete a run, real data or a home
    // folder given by mistake.
    require(empty || fs::exists(fs::path(dir) / "synth_info.json", ec),
            dir +
                ": is not a dataset written by neraf synth (no synth_info.json), so --force "
                "does not replace it; choose a new or empty --out folder");
    // The whole folder is replaced: anything else in it (a run trained inside it, notes) would
    // go with it.
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const std::string name = entry.path().filename().string();
      const bool ours = name == ".neraf_cache" || name == "binaural_rirs" || name == "data" ||
                        name == "images" || name == "metadata" || name == "metadata_AudioNeRF" ||
                        name == "plan.png" || name == "scene.json" || name == "synth_info.json" ||
                        name == "transforms.json";
      require(ours, dir + ": holds " + name +
                        ", which neraf synth did not write; --force replaces the whole folder, "
                        "so move it out first (or choose a new --out)");
    }
  }
}

// Runs body(i) for i in [0, n) on all OpenMP threads (dynamic schedule) with a progress bar drawn
// by thread 0; rethrows the first exception after the loop (exceptions cannot leave OpenMP
// regions).
template <typename Body>
void parallel_for_with_progress(int64_t n, Progress* progress, Body body) {
  std::atomic<int64_t> done{0};
  std::exception_ptr error;
  std::atomic<bool> failed{false};
#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t i = 0; i < n; ++i) {
    if (failed.load(std::memory_order_relaxed)) continue;
    try {
      body(i);
    } catch (...) {
#pragma omp critical(neraf_synth_error)
      if (!error) error = std::current_exception();
      failed = true;
    }
    const int64_t d = ++done;
    if (progress && omp_get_thread_num() == 0) progress->update(d);
  }
  if (error) std::rethrow_exception(error);
}

// Writes the whole dataset of `plan` into the folder `root`.
SynthSummary write_dataset(const Scene& scene, const SynthOptions& options, const SynthPlan& plan,
                           const fs::path& root) {
  const auto out = [&](const std::string& rel) { return (root / rel).string(); };
  const bool soundspaces = plan.layout == "soundspaces";

  SynthSummary sum;
  sum.layout = plan.layout;
  sum.sample_rate = plan.sample_rate;
  sum.channels = plan.binaural ? 2 : 1;
  sum.num_microphones = static_cast<int>(plan.microphones.size());
  sum.num_headings = plan.binaural ? static_cast<int>(plan.headings_deg.size()) : 1;
  sum.num_sources = static_cast<int>(scene.sources.size());
  sum.num_rirs = static_cast<int64_t>(plan.jobs.size());
  ProgressOptions popt;
  popt.enabled = options.progress;

  // ---- pictures
  const auto t_images = std::chrono::steady_clock::now();
  std::vector<FrameRecord> frames;
  {
    std::vector<std::pair<const CameraView*, std::string>> shots;
    for (size_t i = 0; i < plan.train_cameras.size(); ++i)
      shots.emplace_back(&plan.train_cameras[i],
                         soundspaces ? frame_file_name("train_", int(i)) : "");
    for (size_t i = 0; i < plan.eval_cameras.size(); ++i)
      shots.emplace_back(&plan.eval_cameras[i],
                         soundspaces ? frame_file_name("eval_", int(i)) : "");
    if (!soundspaces) {  // RAF: one numbered sequence; the reader's 90 % fraction rule splits it
      for (size_t i = 0; i < shots.size(); ++i) shots[i].second = frame_file_name("", int(i));
    }
    const ImageRenderer renderer(scene);
    popt.unit = "img";
    Progress progress("images", static_cast<int64_t>(shots.size()), popt);
    for (size_t i = 0; i < shots.size(); ++i) {
      const RgbImage img =
          renderer.render(*shots[i].first, scene.cameras.supersampling);  // OpenMP rows
      io::write_png(out(shots[i].second), img.width, img.height, 3, img.pixels.data());
      frames.push_back({shots[i].second, shots[i].first->pose});
      progress.update(static_cast<int64_t>(i + 1));
    }
    progress.finish();
    const CameraIntrinsics k = camera_intrinsics(scene.cameras);
    io::write_json_atomically(out("transforms.json"),
                              nerfstudio_transforms(k, frames, soundspaces));
    if (soundspaces) {
      sum.num_train_images = static_cast<int>(plan.train_cameras.size());
      sum.num_eval_images = static_cast<int>(plan.eval_cameras.size());
    } else {
      sum.num_train_images = static_cast<int>(fraction_train_indices(int(frames.size())).size());
      sum.num_eval_images = static_cast<int>(frames.size()) - sum.num_train_images;
    }
  }
  sum.image_seconds = seconds_since(t_images);

  // ---- impulse responses
  const auto t_rirs = std::chrono::steady_clock::now();
  std::unique_ptr<Hrtf> hrtf;
  if (plan.binaural) {
    hrtf = options.hrtf_path.empty() ? std::make_unique<Hrtf>(plan.sample_rate)
                                     : std::make_unique<Hrtf>(plan.sample_rate, options.hrtf_path);
  }
  RirSimOptions sim_options;
  sim_options.binaural = plan.binaural;
  sim_options.seed = derive_seed(options.seed, "rir-tail");
  const RirSimulator simulator(scene, plan.sample_rate, hrtf.get(), sim_options);
  const auto render = [&](const RirJob& job) {
    return simulator.render(scene.sources[job.source], plan.microphones[job.microphone],
                            job.mic_yaw_deg);
  };
  const auto peak_of = [](const std::vector<std::vector<float>>& channels) {
    double p = 0;
    for (const auto& ch : channels)
      for (float v : ch) p = std::max(p, double(std::abs(v)));
    return p;
  };

  // The gain: the loudest RIRs are those of the closest source-microphone pairs (the direct path
  // dominates the peak), so their peak - over every heading - bounds the whole set.
  if (options.gain > 0) {
    sum.gain = options.gain;
  } else {
    std::vector<size_t> order(plan.jobs.size());
    std::iota(order.begin(), order.end(), size_t{0});
    const auto dist = [&](size_t i) {
      return norm(scene.sources[plan.jobs[i].source].position -
                  plan.microphones[plan.jobs[i].microphone]);
    };
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return dist(a) < dist(b); });
    const size_t n_probe =
        std::min<size_t>(order.size(), 4 * std::max<size_t>(plan.headings_deg.size(), 1));
    std::vector<double> peaks(n_probe, 0.0);
    parallel_for_with_progress(static_cast<int64_t>(n_probe), nullptr,
                               [&](int64_t i) { peaks[i] = peak_of(render(plan.jobs[order[i]])); });
    const double probe_peak = n_probe ? *std::max_element(peaks.begin(), peaks.end()) : 0.0;
    sum.gain = probe_peak > 0.5 ? 0.5 / probe_peak : 1.0;
  }

  std::vector<double> peaks(plan.jobs.size(), 0.0);
  {
    // Folders first, serially, so the parallel writers never race on creating them.
    std::set<fs::path> dirs;
    for (const auto& job : plan.jobs) dirs.insert((root / job.file).parent_path());
    for (const auto& d : dirs) {
      std::error_code ec;
      fs::create_directories(d, ec);
      require(!ec, d.string() + ": cannot create the folder (" + ec.message() +
                       "); choose a writable --out");
    }
  }
  {
    popt.unit = "RIR";
    Progress progress(plan.binaural ? "binaural RIRs" : "RIRs", sum.num_rirs, popt);
    const float gain = static_cast<float>(sum.gain);
    parallel_for_with_progress(sum.num_rirs, &progress, [&](int64_t i) {
      const RirJob& job = plan.jobs[i];
      auto channels = render(job);
      for (auto& ch : channels)
        for (float& v : ch) v *= gain;
      peaks[i] = peak_of(channels);
      io::write_audio(out(job.file), {plan.sample_rate, std::move(channels)},
                      io::AudioFormat::wav_float);
      if (!soundspaces) {
        const std::string dir = "data/" + job.name + "/";
        io::write_text_atomically(out(dir + "rx_pos.txt"),
                                  raf_rx_pos(plan.microphones[job.microphone]));
        const Source& src = scene.sources[job.source];
        io::write_text_atomically(out(dir + "tx_pos.txt"), raf_tx_pos(src.position, src.yaw_deg));
      }
    });
    progress.finish();
  }
  sum.peak = peaks.empty() ? 0.0 : *std::max_element(peaks.begin(), peaks.end());
  if (sum.peak > 1.0) {
    const auto n_loud = std::count_if(peaks.begin(), peaks.end(), [](double p) { return p > 1.0; });
    char peak[32];
    std::snprintf(peak, sizeof peak, "%.4g", sum.peak);
    warn(std::to_string(n_loud) + " RIRs exceed 1.0 in amplitude (peak " + peak +
         ") and will be clipped by NeRAF-style loaders; " +
         (options.gain > 0 ? "the gain of --gain-from (" + std::to_string(options.gain) +
                                 ") is too large for this scene"
                           : std::string("move sources away from the microphones")));
  }
  const auto n_silent = std::count(peaks.begin(), peaks.end(), 0.0);
  if (n_silent > 0) {
    warn(std::to_string(n_silent) + " of " + std::to_string(peaks.size()) +
         " RIRs are all zeros (the sound does not reach those microphones within "
         "acoustics.rir_length_s, or every path is blocked); neraf info lists them");
  }
  sum.rir_seconds = seconds_since(t_rirs);

  // ---- metadata
  std::vector<std::string> names;
  for (const auto& job : plan.jobs) names.push_back(job.name);
  const uint64_t split_seed = derive_seed(options.seed, "split");
  if (soundspaces) {
    std::vector<Vec3> points = plan.microphones;
    for (const auto& s : scene.sources) points.push_back(s.position);
    io::write_text_atomically(out("metadata/points.txt"), soundspaces_points_txt(points));
    const json split = soundspaces_split(names, split_seed);
    sum.num_train_rirs = static_cast<int64_t>(split["train"].size());
    sum.num_test_rirs = static_cast<int64_t>(split["test"].size());
    io::write_json_atomically(out("metadata_AudioNeRF/split.json"), split);
  } else {
    const json split = raf_data_split(names, split_seed);
    sum.num_train_rirs = static_cast<int64_t>(split["train"][0].size());
    sum.num_test_rirs = static_cast<int64_t>(split["test"][0].size());
    io::write_json_atomically(out("metadata/data-split.json"), split);
  }
  io::write_json_atomically(out("scene.json"), scene_to_json(scene));
  write_plan_png(out("plan.png"), draw_plan(scene, plan));

  const auto t60 = simulator.eyring_t60();
  json info = {{"generator", "neraf synth"},
               {"layout", sum.layout},
               {"seed", options.seed},
               {"sample_rate", sum.sample_rate},
               {"channels", sum.channels},
               {"rir_length_samples", simulator.length_samples()},
               {"gain", sum.gain},
               {"peak", sum.peak},
               {"num_microphones", sum.num_microphones},
               {"num_headings", sum.num_headings},
               {"num_sources", sum.num_sources},
               {"num_rirs", sum.num_rirs},
               {"num_train_rirs", sum.num_train_rirs},
               {"num_test_rirs", sum.num_test_rirs},
               {"num_train_images", sum.num_train_images},
               {"num_eval_images", sum.num_eval_images},
               {"octave_bands_hz", kOctaveBandsHz},
               {"eyring_t60_s", t60}};
  if (plan.binaural) info["hrtf"] = hrtf->path();
  io::write_json_atomically(out("synth_info.json"), info);
  return sum;
}

}  // namespace

SynthSummary synthesize(const Scene& scene, const SynthOptions& options) {
  const auto t_start = std::chrono::steady_clock::now();
  validate_scene(scene, "scene " + json_quoted(scene.name));
  check_synthesis_size(scene, options.layout, "scene " + json_quoted(scene.name));
  const SynthPlan plan = plan_synthesis(scene, options.layout, options.seed);
  check_sound_reaches_microphones(scene, plan, "scene " + json_quoted(scene.name));
  check_out_dir(options.out_dir, options.force);
  // A failure (bad HRTF, full disk, Ctrl-C) leaves no half-written dataset behind.
  SynthSummary sum;
  io::write_folder_atomically(
      options.out_dir,
      [&](const std::string& tmp) { sum = write_dataset(scene, options, plan, tmp); },
      options.force ? io::FolderWrite::replace : io::FolderWrite::create);
  sum.out_dir = options.out_dir;
  sum.total_seconds = seconds_since(t_start);
  return sum;
}

std::optional<double> synthesized_gain(const std::string& dataset_dir) {
  const std::string path = (fs::path(dataset_dir) / "synth_info.json").string();
  if (!fs::exists(path)) return std::nullopt;
  const json info = io::read_json(path);
  const json gain = info.is_object() ? info.value("gain", json()) : json();
  // synthesize never raises the level (gain = min(1, 0.5 / peak)), and a gain below 1e-12 would
  // put every sample under float's resolution of the 0.5 peak.
  require(gain.is_number() && gain.get<double>() >= 1e-12 && gain.get<double>() <= 1,
          path +
              ": \"gain\" must be a number in [1e-12, 1], as neraf synth writes it; "
              "synthesise that folder again");
  return gain.get<double>();
}

namespace {

std::optional<std::string> scene_json_difference(json room_a, json room_b) {
  if (!room_a.is_object() || !room_b.is_object()) return std::nullopt;  // not ours to judge
  for (json* room : {&room_a, &room_b})
    for (const char* placement : {"name", "microphones", "sources", "cameras"})
      room->erase(placement);
  for (const auto& [key, value] : room_a.items())
    if (room_b.value(key, json()) != value) return key;
  for (const auto& [key, value] : room_b.items())
    if (!room_a.contains(key)) return key;
  return std::nullopt;
}

}  // namespace

std::optional<std::string> room_difference(const std::string& dataset_a,
                                           const std::string& dataset_b) {
  const fs::path a = fs::path(dataset_a) / "scene.json", b = fs::path(dataset_b) / "scene.json";
  if (!fs::exists(a) || !fs::exists(b)) return std::nullopt;
  return scene_json_difference(io::read_json(a.string()), io::read_json(b.string()));
}

std::optional<std::string> room_difference(const Scene& scene, const std::string& dataset) {
  const fs::path b = fs::path(dataset) / "scene.json";
  if (!fs::exists(b)) return std::nullopt;
  return scene_json_difference(scene_to_json(scene), io::read_json(b.string()));
}

}  // namespace neraf::sim
