#include "neraf/infer/exported_model.h"

#include <ATen/CPUGeneratorImpl.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "neraf/io/atomic_file.h"
#include "neraf/io/signal_cleanup.h"
#include "neraf/neraf_rt.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::infer {

namespace {

rt::DenseLayer dense_layer(const torch::Tensor& weight, const torch::Tensor& bias) {
  const torch::Tensor w = weight.detach().to(torch::kCPU, torch::kFloat32).contiguous();  // [O, I]
  const torch::Tensor b = bias.detach().to(torch::kCPU, torch::kFloat32).contiguous();    // [O]
  rt::DenseLayer layer;
  layer.out = w.size(0);
  layer.in = w.size(1);
  layer.weight.assign(w.data_ptr<float>(), w.data_ptr<float>() + w.numel());
  layer.bias.assign(b.data_ptr<float>(), b.data_ptr<float>() + b.numel());
  return layer;
}

// The parameter `name` of `module` (e.g. "field.soundfield.0.weight").
torch::Tensor parameter(const torch::nn::Module& module, const std::string& name) {
  for (const auto& p : module.named_parameters(true))
    if (p.key() == name) return p.value();
  throw Error("export: the acoustic model has no parameter " + name + " (a neraf bug)");
}

nlohmann::json export_metadata(const AudioRun& run) {
  const LoadedRun& r = run.run();
  return {{"format", "neraf acoustic field"},
          {"frame",
           "positions in metres in the dataset's frame as NeRAF reads it (SoundSpaces: y up, a "
           "points.txt row x y z is x, z, -y; RAF as written); yaw in degrees: the receiver "
           "heading for SoundSpaces, the source yaw for RAF"},
          {"run", fs::absolute(r.run_dir).lexically_normal().string()},
          {"checkpoint", fs::path(r.checkpoint).filename().string()},
          {"step", r.step},
          {"preset", r.config.preset},
          {"modality", to_string(r.config.modality)},
          {"grid", acoustic::to_string(run.model()->options().grid_mode)},
          {"seed", r.config.seed},
          {"audio_fraction", r.config.audio.fraction},
          {"calibration", run.calibration().defined()},
          {"data", r.manifest}};
}

}  // namespace

rt::ModelData export_model_data(const AudioRun& run, const ExportOptions& options) {
  const AudioRunInfo& info = run.info();
  const acoustic::AcousticModelOptions& mo = run.model()->options();
  const acoustic::NacfOptions& no = mo.nacf;
  require(mo.grid_features == acoustic::GridFeatures::kGlobal,
          run.run().run_dir + ": trained with --grid-features " +
              acoustic::to_string(mo.grid_features) +
              "; the runtime takes the published design (one scene feature per room) only, so "
              "this run cannot be exported; query it with neraf render / eval --run instead");
  require(!no.decay_heads,
          run.run().run_dir +
              ": trained with --decay-heads, which the runtime does not evaluate, so this run "
              "cannot be exported; query it with neraf render / eval --run instead");
  rt::ModelData m;
  m.neraf_version = NERAF_VERSION;
  m.layout = info.layout == data::AudioLayout::raf ? 1 : 0;
  m.sample_rate = info.sample_rate;
  m.channels = info.channels;
  m.n_fft = info.stft.n_fft;
  m.win_length = info.stft.win_length;
  m.hop_length = info.stft.hop_length;
  m.n_freq = static_cast<int>(info.n_freq);
  m.max_len = static_cast<int>(info.max_len);
  m.time_frames = static_cast<int>(info.time_frames);
  m.waveform_length = info.waveform_length;
  m.box_min = {info.aabb.min.x, info.aabb.min.y, info.aabb.min.z};
  m.box_max = {info.aabb.max.x, info.aabb.max.y, info.aabb.max.z};
  m.relative_geometry = no.relative_geometry;
  m.position_max_freq_exp = no.position_max_freq_exp;
  m.extent_m = no.extent_m();
  m.leaky_slope = no.leaky_slope;
  m.output_scale = no.output_scale;
  m.bf16_storage = options.bf16;
  m.metadata_json = export_metadata(run).dump();

  const torch::nn::Module& module = *run.model();
  for (size_t i = 0; i < no.trunk.size(); ++i) {
    const std::string p = "field.soundfield." + std::to_string(i);
    torch::Tensor w = parameter(module, p + ".weight").detach().to(torch::kFloat64);  // [H1, in]
    torch::Tensor b = parameter(module, p + ".bias").detach().to(torch::kFloat64);    // [H1]
    if (i == 0) {
      // The model's input order → the runtime's canonical [time, mic, src, rot, relative].
      const int64_t g = no.grid_features, t = acoustic::kTimeEncodingDim,
                    pos = acoustic::kPositionEncodingDim, rot = acoustic::kRotEncodingDim;
      const torch::Tensor rest =
          w.narrow(1, g + acoustic::kPoseEncodingDim, w.size(1) - g - acoustic::kPoseEncodingDim);
      if (mo.grid_mode == acoustic::GridMode::kNone) {  // [mic, src, time, rot, relative]
        w = torch::cat(
            {w.narrow(1, 2 * pos, t), w.narrow(1, 0, 2 * pos), w.narrow(1, 2 * pos + t, rot), rest},
            1);
      } else {  // [g, time, mic, src, rot, relative]: fold the constant feature into the bias
        const torch::Tensor feature =
            run.scene_features().global.detach().to(torch::kCPU, torch::kFloat64);
        require(feature.defined() && feature.numel() == g,
                "export: the run's scene feature does not match its model (a neraf bug)");
        b = b + torch::mv(w.narrow(1, 0, g), feature);
        w = w.narrow(1, g, w.size(1) - g);
      }
    }
    m.trunk.push_back(dense_layer(w, b));
  }
  for (int64_t c = 0; c < no.n_channels; ++c) {
    const std::string p = "field.STFT_linear." + std::to_string(c);
    m.heads.push_back(
        dense_layer(parameter(module, p + ".weight"), parameter(module, p + ".bias")));
  }
  if (run.calibration().defined()) {
    const torch::Tensor g =
        run.calibration().detach().to(torch::kCPU, torch::kFloat32).contiguous();
    m.calibration.assign(g.data_ptr<float>(), g.data_ptr<float>() + g.numel());  // [C, F, T]
  }
  if (options.bf16) {  // what the file will hold, so the check below compares like for like
    for (auto* layers : {&m.trunk, &m.heads})
      for (rt::DenseLayer& l : *layers)
        for (float& x : l.weight) x = rt::bf16_to_float(rt::float_to_bf16(x));
  }
  rt::check_model_data(m, "export");
  return m;
}

ExportReport export_model(const AudioRun& run, const std::string& path,
                          const ExportOptions& options, int64_t check_poses) {
  const rt::ModelData data = export_model_data(run, options);
  // Written and checked under a temporary name beside `path`, then renamed over it: a failed
  // check leaves whatever was at `path` untouched (and a killed export's file is removed by the
  // next one, io/atomic_file.h).
  io::require_replaceable_file(path);
  const fs::path folder = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : ".";
  io::remove_stale_temporaries(folder.string());
  const std::string candidate = path + io::temporary_suffix();
  const io::RemoveOnSignal remove_on_ctrl_c(candidate);
  try {
    rt::write_model_file(candidate, data);
  } catch (const std::exception& e) {
    throw Error(io::with_user_path(e.what(), candidate, path));
  }
  std::error_code ec;
  struct RemoveCandidate {
    const std::string& file;
    ~RemoveCandidate() {
      std::error_code ignored;
      fs::remove(file, ignored);  // nothing once renamed
    }
  } cleanup{candidate};
  ExportReport report;
  report.file_bytes = static_cast<int64_t>(fs::file_size(candidate, ec));

  // The file as the runtime reads it, against the LibTorch path, at poses over the box.
  const ExportedModel model = load_exported_model(candidate);
  const data::Aabb& box = run.info().aabb;
  // Own generator: exporting does not move the global RNG, and the check is reproducible.
  const at::Generator gen = at::detail::createCPUGenerator(20250101);
  const torch::Tensor u = torch::rand({check_poses, 7}, gen, torch::kFloat64);
  const torch::Tensor lo = torch::tensor({box.min.x, box.min.y, box.min.z}, torch::kFloat64);
  const torch::Tensor size = torch::tensor(
      {box.max.x - box.min.x, box.max.y - box.min.y, box.max.z - box.min.z}, torch::kFloat64);
  const torch::Tensor mic = lo + u.narrow(1, 0, 3) * size;  // [N, 3]
  // Sources: the first half over the box, the second over the box grown by half its size on each
  // side, so most of those lie outside it (as RAF loudspeakers often do), where both paths must
  // still agree (zero position encoding, relative geometry from the metres).
  const torch::Tensor grown = (torch::arange(check_poses) >= check_poses / 2).to(torch::kFloat64);
  const torch::Tensor spread = (1.0 + grown).unsqueeze(1);  // [N, 1]: 1 inside, 2 grown
  const torch::Tensor src = lo + (u.narrow(1, 3, 3) * spread - (spread - 1.0) / 2.0) * size;
  const torch::Tensor yaw = u.select(1, 6) * 360.0;  // [N]
  const torch::Tensor ours = model.predict_log_stft_batch(mic, src, yaw);
  const torch::Tensor reference = run.predict_log_stft_batch(mic, src, yaw);
  report.max_abs_difference = (ours - reference).abs().max().item<double>();
  report.poses_checked = check_poses;
  // fp32: float rounding in another summation order (measured ~3e-6); bf16: the rounded weights
  // (and bf16 activations where the CPU computes in bf16; measured ~1e-2). Far above either means
  // the file does not hold this field: it is not left behind.
  const double tolerance = options.bf16 ? 0.25 : 1e-3;
  require(report.max_abs_difference <= tolerance,
          path + ": the exported model disagrees with the run (max |Δ log-STFT| " +
              std::to_string(report.max_abs_difference) + " > " + std::to_string(tolerance) +
              "); not written. This is a neraf bug: please report it with the run's config.json");
  fs::rename(candidate, path, ec);
  require(!ec, path + ": cannot rename the checked model into place (" + ec.message() + ")");
  io::sync_path(folder.string());
  return report;
}

torch::Tensor ExportedModel::predict_log_stft_batch(const torch::Tensor& mic,
                                                    const torch::Tensor& src,
                                                    const torch::Tensor& yaw_deg) const {
  TORCH_CHECK(mic.dim() == 2 && mic.size(1) == 3 && src.sizes() == mic.sizes() &&
                  yaw_deg.dim() == 1 && yaw_deg.size(0) == mic.size(0),
              "ExportedModel: expected mic, src [N, 3] and yaw [N]");
  const int64_t n = mic.size(0);
  const torch::Tensor m = mic.to(torch::kFloat64).contiguous();
  const torch::Tensor s = src.to(torch::kFloat64).contiguous();
  const torch::Tensor y = yaw_deg.to(torch::kFloat64).contiguous();
  torch::Tensor out = torch::empty({n, info_.channels, info_.n_freq, info_.max_len});
  neraf_workspace* raw = nullptr;
  if (neraf_workspace_create(model_.get(), &raw) != NERAF_OK)
    throw Error(path_ + ": " + neraf_last_error());
  std::unique_ptr<neraf_workspace, void (*)(neraf_workspace*)> ws(raw, neraf_workspace_free);
  const unsigned flags = allow_outside_ ? NERAF_ALLOW_OUTSIDE : 0u;
  const auto ma = m.accessor<double, 2>(), sa = s.accessor<double, 2>();
  const auto ya = y.accessor<double, 1>();
  for (int64_t i = 0; i < n; ++i) {
    neraf_pose pose;
    for (int k = 0; k < 3; ++k) {
      pose.mic[k] = ma[i][k];
      pose.source[k] = sa[i][k];
    }
    pose.yaw_deg = ya[i];
    if (neraf_query_log_stft(model_.get(), ws.get(), &pose, flags, out[i].data_ptr<float>(),
                             static_cast<size_t>(out[i].numel())) != NERAF_OK)
      throw Error(path_ + ": " + neraf_last_error());
  }
  return out;  // [N, C, F, T]
}

ExportedModel load_exported_model(const std::string& path) {
  neraf_model* raw = nullptr;
  if (neraf_model_load(path.c_str(), &raw) != NERAF_OK) throw Error(neraf_last_error());
  ExportedModel out;
  out.path_ = path;
  out.model_ = std::shared_ptr<neraf_model>(raw, neraf_model_free);
  neraf_model_info mi;
  if (neraf_model_get_info(raw, &mi) != NERAF_OK) throw Error(path + ": " + neraf_last_error());
  AudioRunInfo& info = out.info_;
  info.layout = mi.layout == 1 ? data::AudioLayout::raf : data::AudioLayout::soundspaces;
  info.sample_rate = mi.sample_rate;
  info.stft.n_fft = mi.n_fft;
  info.stft.win_length = mi.win_length;
  info.stft.hop_length = mi.hop_length;
  info.stft.center = true;
  info.n_freq = mi.n_freq;
  info.max_len = mi.n_frames;
  info.channels = mi.channels;
  info.waveform_length = mi.rir_length;
  info.aabb.min = {mi.box_min[0], mi.box_min[1], mi.box_min[2]};
  info.aabb.max = {mi.box_max[0], mi.box_max[1], mi.box_max[2]};
  try {
    out.metadata_ = nlohmann::json::parse(rt::read_model_file(path).metadata_json);
  } catch (const std::exception&) {
    out.metadata_ = nlohmann::json::object();
  }
  return out;
}

}  // namespace neraf::infer
