#include "neraf/infer/audio_run.h"

#include <ATen/CPUGeneratorImpl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "neraf/acoustic/calibration.h"
#include "neraf/dsp/griffin_lim.h"
#include "neraf/infer/calibration.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/io/json_file.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace fs = std::filesystem;

namespace neraf::infer {

namespace {

// FNV-1a over the RIR ids, split membership, headings and poses (µm), so any change of the
// dataset's content that the acoustic field depends on changes the hash.
std::string dataset_hash(const data::RirSet& r) {
  uint64_t h = 1469598103934665603ULL;
  auto mix = [&](const std::string& s) {
    for (unsigned char c : s) {
      h ^= c;
      h *= 1099511628211ULL;
    }
    h ^= 0xff;
    h *= 1099511628211ULL;
  };
  char buf[160];
  for (const data::Rir& x : r.rirs) {
    std::snprintf(buf, sizeof buf, "%d %.6f %.6f %.6f %.6f %.6f %.6f", x.heading_deg, x.mic.x,
                  x.mic.y, x.mic.z, x.source.x, x.source.y, x.source.z);
    mix(x.id);
    mix(buf);
  }
  for (int64_t i : r.train) mix(std::to_string(i));
  char out[17];
  std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
  return out;
}

nlohmann::json vec_json(const geometry::Vec3& v) { return {v.x, v.y, v.z}; }

}  // namespace

nlohmann::json make_audio_manifest(const data::RirSet& r) {
  nlohmann::json m = {{"layout", data::to_string(r.layout)},
                      {"num_rirs", r.size()},
                      {"num_train", static_cast<int64_t>(r.train.size())},
                      {"num_test", static_cast<int64_t>(r.test.size())},
                      {"hash", dataset_hash(r)},
                      {"sample_rate", r.sample_rate},
                      {"channels", r.channels},
                      {"n_fft", r.stft.n_fft},
                      {"win_length", r.stft.win_length},
                      {"hop_length", r.stft.hop_length},
                      {"n_freq", r.n_freq},
                      {"max_len", r.max_len},
                      {"waveform_length", r.waveform_length},
                      {"aabb_min", vec_json(r.audio_aabb.min)},
                      {"aabb_max", vec_json(r.audio_aabb.max)}};
  if (!r.sources_hash().empty()) m["sources_fnv1a"] = r.sources_hash();
  if (!r.max_len_source.empty()) m["max_len_source"] = r.max_len_source;
  if (!r.max_len_note.empty()) m["max_len_note"] = r.max_len_note;
  return m;
}

void check_audio_manifest(const nlohmann::json& manifest, const data::RirSet& rirs,
                          const std::string& where) {
  const nlohmann::json now = make_audio_manifest(rirs);
  for (const char* key :
       {"layout", "num_rirs", "num_train", "hash", "channels", "n_freq", "max_len"}) {
    // A value of another JSON type is a damaged run, not another dataset.
    const nlohmann::json& was = manifest.value(key, nlohmann::json());
    require(was.is_null() || was.type() == now[key].type() ||
                (was.is_number_integer() && now[key].is_number_integer()),
            std::string("the run's data.json is damaged (audio.") + key + " is " + was.dump() +
                ", a " + was.type_name() + "; expected a " + now[key].type_name() +
                "); restore it or train a new run");
    require(was == now[key],
            where + ": was trained on another RIR dataset (" + key + " differs: " + was.dump() +
                " vs " + now[key].dump() +
                "); use the original --data (or, for neraf train, a new --out folder)");
  }
  // The files' contents: runs and caches from before the hash have none, then the ids and poses
  // above are all there is.
  const nlohmann::json recorded = manifest.value("sources_fnv1a", nlohmann::json(""));
  require(recorded.is_string(), "the run's data.json is damaged (audio.sources_fnv1a is " +
                                    recorded.dump() + "); restore it or train a new run");
  const std::string was = recorded, is = rirs.sources_hash();
  require(was.empty() || is.empty() || was == is,
          where +
              ": its RIR files changed since the run was trained (same names and poses, other "
              "contents: sources_fnv1a " +
              was + " vs " + is +
              "); restore the original files (or, for neraf train, use a new --out folder)");
}

void check_same_room_format(const nlohmann::json& manifest, const data::RirSet& rirs,
                            const std::string& where) {
  const nlohmann::json now = make_audio_manifest(rirs);
  for (const char* key : {"layout", "sample_rate", "channels", "n_fft", "win_length", "hop_length",
                          "n_freq", "max_len", "waveform_length"})
    require(manifest.value(key, nlohmann::json()) == now[key],
            where + ": its " + key + " (" + now[key].dump() + ") differs from the run's (" +
                manifest.value(key, nlohmann::json()).dump() +
                "); synthesise or convert it in the run's format");
}

acoustic::AcousticModelOptions audio_model_options(const TrainConfig& config, int64_t channels,
                                                   int64_t n_freq, int64_t max_len,
                                                   const data::Aabb& audio_aabb,
                                                   const acoustic::WorldToField& world_to_field) {
  acoustic::AcousticModelOptions o =
      acoustic::acoustic_preset(config.preset, channels, n_freq, max_len);
  const AudioConfig& a = config.audio;
  o.grid_mode = acoustic::parse_grid_mode(a.grid);
  o.grid_features = acoustic::parse_grid_features(a.grid_features);
  o.grid.view_directions = acoustic::parse_view_directions(a.view_directions);
  o.resnet.running_stats = a.resnet_batch_norm == "running";
  o.grid.resolution = a.grid_resolution;
  o.grid.cells_per_update = a.cells_per_update;
  if (a.nacf_width > 0) o.nacf.trunk.assign(static_cast<size_t>(a.nacf_layers), a.nacf_width);
  // The NAcF trunk follows --precision, as the radiance field's MLPs.
  o.nacf.bf16 = config.model.precision == nerf::Precision::bf16;
  o.nacf.relative_geometry = a.relative_geometry;
  o.nacf.position_max_freq_exp = a.position_max_freq_exp;
  o.nacf.decay_heads = a.decay_heads;
  o.nacf.box_min = {audio_aabb.min.x, audio_aabb.min.y, audio_aabb.min.z};
  o.nacf.box_max = {audio_aabb.max.x, audio_aabb.max.y, audio_aabb.max.z};
  o.nacf.world_to_field = world_to_field;
  return o;
}

std::vector<int64_t> audio_train_subset(const data::RirSet& rirs, double fraction, uint64_t seed) {
  require(fraction > 0 && fraction <= 1,
          "the audio fraction (neraf train --audio-fraction) must be in (0, 1], not " +
              std::to_string(fraction));
  std::vector<int64_t> all = rirs.train;
  if (fraction >= 1.0 || all.empty()) return all;
  const int64_t n = static_cast<int64_t>(all.size());
  const int64_t k = std::max<int64_t>(1, std::llround(fraction * static_cast<double>(n)));
  // Own generator (not the run's stream) so the subset only depends on --seed and the fraction.
  at::Generator gen = at::make_generator<at::CPUGeneratorImpl>(seed ^ 0x9e3779b97f4a7c15ULL);
  const torch::Tensor perm = torch::randperm(n, gen, torch::kInt64);
  std::vector<int64_t> out;
  for (int64_t i = 0; i < k; ++i) out.push_back(all[static_cast<size_t>(perm[i].item<int64_t>())]);
  std::sort(out.begin(), out.end());
  return out;
}

torch::Tensor AudioRun::predict_pose(const torch::Tensor& mic_m, const torch::Tensor& src_m,
                                     const torch::Tensor& rot) const {
  // [C, F, T]: a scene of a multi-scene run is cut to its own frames.
  const torch::Tensor raw =
      model_->render_stft_with_feature(features_, mic_m, src_m, rot).narrow(2, 0, info_.max_len);
  return calibration_.defined() ? acoustic::apply_calibration(raw, calibration_)
                                : raw;  // [C, F, T]
}

torch::Tensor AudioRun::predict_log_stft_batch(const torch::Tensor& mic, const torch::Tensor& src,
                                               const torch::Tensor& yaw_deg) const {
  const torch::Tensor m = mic.to(torch::kFloat64), s = src.to(torch::kFloat64);
  const torch::Tensor th = yaw_deg.to(torch::kFloat64) * (M_PI / 180.0);
  const torch::Tensor rot = torch::stack(
      {(torch::cos(th) + 1) / 2, torch::full_like(th, 0.5), (torch::sin(th) + 1) / 2}, 1);
  std::vector<torch::Tensor> out;
  for (int64_t i = 0; i < m.size(0); ++i) out.push_back(predict_pose(m[i], s[i], rot[i]));
  return torch::stack(out);  // [N, C, F, T]
}

AudioRun load_audio_run(const std::string& run_dir, torch::Device device,
                        const std::string& checkpoint, nerf::Precision precision, bool calibrated,
                        int64_t scene) {
  const std::string config_path = run_config_file(run_dir);
  const std::string manifest_path = (fs::path(run_dir) / "data.json").string();
  AudioRun out;
  out.run_.run_dir = run_dir;
  out.run_.config = read_run_config(config_path);
  require(out.run_.config.modality != Modality::vision,
          run_dir +
              ": this run has no acoustic field (trained with --modality vision); train "
              "with --modality joint or audio");
  out.run_.manifest = io::read_json(manifest_path);
  check_data_paths(out.run_.manifest, manifest_path);
  if (is_multiscene(out.run_.manifest)) {
    const std::vector<std::string> names = scene_names(out.run_.manifest);
    std::string list;
    for (size_t i = 0; i < names.size(); ++i)
      list += (i ? ", " : "") + std::to_string(i) + " " + names[i];
    require(scene >= 0, run_dir + ": a multi-scene run (" + std::to_string(names.size()) +
                            " scenes: " + list + "); pick one with --scene NAME|INDEX");
    require(scene < static_cast<int64_t>(names.size()),
            run_dir + ": has no scene " + std::to_string(scene) + " (its scenes: " + list + ")");
    const nlohmann::json one = out.run_.manifest["scenes"][static_cast<size_t>(scene)];
    out.run_.manifest = one;
    out.scene_ = scene;
  } else {
    require(scene <= 0, run_dir + ": a one-scene run has no scene " + std::to_string(scene));
  }
  require(out.run_.manifest.contains("audio"),
          manifest_path + ": no audio manifest; re-run neraf train with --modality joint");
  out.info_ = audio_info_from_manifest(out.run_.manifest["audio"], manifest_path);
  out.run_.checkpoint = checkpoint_of_run(run_dir, checkpoint);
  const AudioRunInfo& info = out.info_;
  acoustic::AcousticModelOptions opts = audio_model_options(
      out.run_.config, info.channels, info.n_freq, info.model_frames(), info.aabb,
      out.run_.config.audio.grid_features == "global"
          ? acoustic::kIdentityWorldToField  // not read
          : world_to_field(out.run_.manifest, manifest_path));
  // Queries run in fp32 unless asked (bf16 training keeps fp32 master weights): the numbers of
  // eval and render then do not depend on the machine, and match an fp32 export.
  opts.nacf.bf16 = precision == nerf::Precision::bf16;
  out.model_ = acoustic::AcousticModel(opts);
  acoustic::GridSampler grid(opts.grid);
  torch::serialize::InputArchive a;
  load_archive(a, out.run_.checkpoint);
  check_checkpoint_header(a, out.run_.config, out.run_.checkpoint);
  try {
    torch::serialize::InputArchive branch, m, g;
    a.read("branch_audio", branch);
    // A run trained with --audio-average is used through its averaged weights.
    if (!branch.try_read("model_average", m)) branch.read("model", m);
    load_module(*out.model_, m, out.run_.checkpoint);
    branch.read(scene_key("grid", out.scene_), g);
    load_module(*grid, g, out.run_.checkpoint);
    torch::Tensor step;
    a.read("step", step);
    out.run_.step = step.item<int64_t>();
    c10::IValue legacy;  // checkpoints written before the calibration stage held their gains
    if (calibrated && out.run_.config.audio.energy_calibration) {
      if (auto gains = load_calibration(out.run_.checkpoint, out.run_.step, out.scene_)) {
        // [C, F, T] of this run's data (a file copied from another run has other sizes).
        require(gains->sizes() == torch::IntArrayRef({info.channels, info.n_freq, info.max_len}),
                calibration_path(out.run_.checkpoint) + ": fitted for another field (gains of " +
                    std::to_string(gains->size(0)) + " channels x " +
                    std::to_string(gains->size(1)) + " bins x " + std::to_string(gains->size(2)) +
                    " frames; the run's data.json has " + std::to_string(info.channels) + " x " +
                    std::to_string(info.n_freq) + " x " + std::to_string(info.max_len) +
                    "); delete it and run neraf calibrate --run " + run_dir);
        out.calibration_ = gains->to(device);
      } else if (branch.try_read("calibration", legacy))
        out.calibration_ = legacy.toTensor().to(device);
      else
        warn(out.run_.checkpoint +
             ": not calibrated (training stopped before its calibration "
             "stage); predictions are uncalibrated until you run: neraf calibrate --run " +
             run_dir);
    }
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    throw Error(out.run_.checkpoint + ": checkpoint does not match the run's config (" +
                what.substr(0, what.find('\n')) + "); it belongs to another run");
  }
  out.model_->to(device);
  grid->to(device);
  out.model_->eval();
  {
    // The scene feature is computed once: eval-mode ResNet3D on the grid saved at that step.
    torch::NoGradGuard no_grad;
    out.features_ = out.model_->scene_features(grid->grid().detach());
  }
  return out;
}

}  // namespace neraf::infer
