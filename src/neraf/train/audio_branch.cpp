#include "neraf/train/audio_branch.h"

#include <ATen/CPUGeneratorImpl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <tuple>

#include "neraf/acoustic/calibration.h"
#include "neraf/acoustic/losses.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/metrics/room_acoustics.h"
#include "neraf/train/distributed.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::train {

using infer::TrainConfig;

AudioBranch::AudioBranch(const TrainConfig& config, const data::RirSet& rirs,
                         nerf::NerfactoModel field, const acoustic::WorldToField& world_to_field,
                         bool frozen_field, torch::Device device)
    : AudioBranch(config, std::vector<const data::RirSet*>{&rirs},
                  std::vector<nerf::NerfactoModel>{std::move(field)}, {world_to_field},
                  frozen_field, device) {}

AudioBranch::AudioBranch(const TrainConfig& config, const std::vector<const data::RirSet*>& scenes,
                         const std::vector<nerf::NerfactoModel>& fields,
                         const std::vector<acoustic::WorldToField>& world_to_field,
                         bool frozen_field, torch::Device device,
                         const std::vector<int64_t>& scene_frames)
    : config_(config), frozen_(frozen_field), device_(device) {
  TORCH_CHECK(
      !scenes.empty() && scenes.size() == fields.size() && scenes.size() == world_to_field.size(),
      "AudioBranch: one radiance field and world map per scene");
  TORCH_CHECK(scene_frames.empty() || scene_frames.size() == scenes.size(),
              "AudioBranch: one frame count per scene");
  require(scenes.size() == 1 || frozen_,
          "multi-scene: only --modality audio (each scene's frozen vision run) is implemented");
  const data::RirSet& first = *scenes.front();
  for (const data::RirSet* r : scenes) {
    require(r->has_features(), "dataset: the RIR features were not loaded");
    require(!r->train.empty(), r->root +
                                   ": the audio train split is empty; the acoustic field "
                                   "needs training RIRs");
    require(
        r->channels == first.channels && r->n_freq == first.n_freq && r->max_len == first.max_len,
        r->root + ": its RIRs differ in channels, frequencies or frames from " + first.root +
            "; one acoustic field needs scenes of one format");
  }
  const acoustic::AcousticModelOptions opts =
      infer::audio_model_options(config_, first.channels, first.n_freq, first.max_len,
                                 first.audio_aabb, world_to_field.front());
  model_ = acoustic::AcousticModel(opts);
  model_->to(device_);
  for (size_t s = 0; s < scenes.size(); ++s) {
    Scene sc;
    sc.rirs = scenes[s];
    sc.field = fields[s];
    sc.grid = acoustic::GridSampler(opts.grid);
    sc.grid->to(device_);
    sc.train_rirs = infer::audio_train_subset(*sc.rirs, config_.audio.fraction, config_.seed);
    sc.offset = n_train_;
    n_train_ += static_cast<int64_t>(sc.train_rirs.size());
    sc.frames = scene_frames.empty() ? sc.rirs->max_len : scene_frames[s];
    TORCH_CHECK(sc.frames >= 1 && sc.frames <= sc.rirs->max_len,
                "AudioBranch: scene frames out of range");
    sc.first_slice = n_slices_;
    n_slices_ += static_cast<int64_t>(sc.train_rirs.size()) * sc.frames;
    // This scene's box (the scene's own pose normalisation and relative-distance scale) and map
    // into its radiance field's frame.
    sc.nacf = model_->options().nacf;
    const data::Aabb& box = sc.rirs->audio_aabb;
    sc.nacf.box_min = {box.min.x, box.min.y, box.min.z};
    sc.nacf.box_max = {box.max.x, box.max.y, box.max.z};
    sc.nacf.world_to_field = world_to_field[s];
    if (opts.grid_features != acoustic::GridFeatures::kGlobal &&
        !std::filesystem::exists(std::filesystem::path(sc.rirs->root) / "synth_info.json"))
      warn(sc.rirs->root + ": --grid-features " + config_.audio.grid_features +
           " reads the grid at the RIR positions mapped by the cameras' world transform, which "
           "assumes the RIRs and the cameras share one frame; neraf synth writes them so, but "
           "this dataset was not made by neraf synth (the published SoundSpaces and RAF frames "
           "are aligned by hand)");
    scenes_.push_back(std::move(sc));
    if (frozen_ && opts.grid_mode == acoustic::GridMode::kSampled) {
      // The paper's separate training: the field is final, so the whole grid is filled once.
      scenes_.back().field->eval();
      scenes_.back().grid->refresh_all(field_query(s));
    }
  }
}

acoustic::FieldQueryFn AudioBranch::field_query(size_t scene) {
  nerf::NerfactoModel field = scenes_[scene].field;
  torch::Device device = device_;
  return [field, device](const torch::Tensor& u, const torch::Tensor& dirs) mutable {
    // Appearance of train image 0, as the reference (camera_indices = 0 in training mode).
    const torch::Tensor app = torch::zeros({1}, torch::dtype(torch::kInt64).device(device));
    nerf::FieldQuery q = field->field->query(u, dirs, app);
    return std::make_pair(q.density, q.rgb);
  };
}

std::vector<ParamGroup> AudioBranch::param_groups() {
  std::vector<torch::Tensor> params = model_->parameters();
  // "Backprop on vision too": the reference's audio optimizer also holds the radiance field.
  if (!frozen_)
    for (auto& p : scenes_.front().field->field_parameters()) params.push_back(p);
  return {{"audio_fields", params, config_.audio.schedule}};
}

void AudioBranch::set_training(bool training) {
  model_->train(training);
  for (Scene& sc : scenes_) sc.grid->train(training);
}

std::pair<torch::Tensor, torch::Tensor> AudioBranch::sample_slices(at::Generator& gen, int64_t D) {
  const int64_t T = scenes_.front().rirs->max_len;
  const int64_t n = n_slices_;
  const int64_t B = config_.audio.batch_size;
  const int64_t B_early = std::llround(config_.audio.early_fraction * static_cast<double>(B));
  const int64_t B_uniform = B - B_early;
  // Uniform share: shuffled (RIR, frame) slices, epoch-wise without replacement (the
  // reference's DataLoader).
  std::vector<int64_t> picks;
  picks.reserve(static_cast<size_t>(B_uniform));
  while (static_cast<int64_t>(picks.size()) < B_uniform) {
    if (!perm_.defined() || cursor_ >= perm_.size(0)) {
      perm_ = torch::randperm(n, gen, torch::kInt64);
      cursor_ = 0;
    }
    const int64_t take =
        std::min(B_uniform - static_cast<int64_t>(picks.size()), perm_.size(0) - cursor_);
    const int64_t* p = perm_.data_ptr<int64_t>() + cursor_;
    picks.insert(picks.end(), p, p + take);
    cursor_ += take;
  }
  // Slice k of scene s (first_slice ≤ k < the next scene's): its train RIR offset + j / frames,
  // frame j % frames, j = k − first_slice. (All frames equal: RIR k / T, frame k % T.)
  std::vector<int64_t> rir_of(picks.size()), frame_of(picks.size());
  for (size_t i = 0; i < picks.size(); ++i) {
    size_t s = scenes_.size() - 1;
    while (scenes_[s].first_slice > picks[i]) --s;
    const int64_t j = picks[i] - scenes_[s].first_slice;
    rir_of[i] = scenes_[s].offset + j / scenes_[s].frames;
    frame_of[i] = j % scenes_[s].frames;
  }
  torch::Tensor local = torch::tensor(rir_of, torch::kInt64);  // position among all train RIRs
  torch::Tensor frame = torch::tensor(frame_of, torch::kInt64);
  // Early share: random train RIRs, frames in [0, early_frames).
  const int64_t n_rirs = n_train_;
  if (B_early > 0) {
    local = torch::cat({local, torch::randint(n_rirs, {B_early}, gen, torch::kInt64)});
    frame = torch::cat({frame, torch::randint(std::min(T, config_.audio.early_frames), {B_early},
                                              gen, torch::kInt64)});
  }
  // Whole RIRs: D distinct train RIRs, all frames in order.
  if (D > 0) {
    const torch::Tensor whole = torch::randperm(n_rirs, gen, torch::kInt64).slice(0, 0, D);
    local = torch::cat({local, whole.repeat_interleave(T)});
    frame = torch::cat({frame, torch::arange(T, torch::kInt64).repeat({D})});
  }
  return {local, frame};
}

std::pair<torch::Tensor, torch::Tensor> AudioBranch::forward_scenes(const torch::Tensor& pos,
                                                                    const torch::Tensor& frame,
                                                                    int64_t B) {
  const int64_t M = pos.size(0);
  const int64_t* p = pos.data_ptr<int64_t>();
  auto scene_of = [&](int64_t g) {
    size_t s = scenes_.size() - 1;
    while (scenes_[s].offset > g) --s;
    return s;
  };
  // Stable per scene within [0, B) and within [B, M), so the whole RIRs stay frame-ordered.
  std::vector<torch::Tensor> preds, gts;
  std::vector<acoustic::SceneFeatures> features(scenes_.size());
  std::vector<bool> encoded(scenes_.size(), false);
  using Range = std::pair<int64_t, int64_t>;
  for (const auto& [lo, hi] : {Range{0, B}, Range{B, M}})
    for (size_t s = 0; s < scenes_.size(); ++s) {
      std::vector<int64_t> rows, rirs;
      for (int64_t j = lo; j < hi; ++j)
        if (scene_of(p[j]) == s) {
          rows.push_back(j);
          rirs.push_back(scenes_[s].train_rirs[static_cast<size_t>(p[j] - scenes_[s].offset)]);
        }
      if (rows.empty()) continue;
      const Scene& sc = scenes_[s];
      const torch::Tensor rir = torch::tensor(rirs, torch::kInt64);
      const torch::Tensor f = frame.index_select(0, torch::tensor(rows, torch::kInt64));
      torch::Tensor gt = torch::empty({rir.size(0), sc.rirs->channels, sc.rirs->n_freq},
                                      torch::kFloat32);  // [b, C, F]
      sc.rirs->gather_into(rir, f, gt);
      if (!encoded[s]) {  // once per scene and step
        features[s] = model_->scene_features(sc.grid->grid());
        encoded[s] = true;
      }
      const torch::Tensor mic = sc.rirs->mic_positions.index_select(0, rir);
      const torch::Tensor src = sc.rirs->source_positions.index_select(0, rir);
      const torch::Tensor rot = sc.rirs->rots.index_select(0, rir);
      preds.push_back(model_->field()->forward(model_->nacf_input(
          features[s], sc.nacf, f.to(device_), mic.to(device_), src.to(device_), rot.to(device_))));
      gts.push_back(gt.to(device_));
    }
  return {torch::cat(preds), torch::cat(gts)};  // [M, C, F] each
}

LossDict AudioBranch::losses(StepContext& ctx) {
  const bool audio_step = ctx.step > config_.audio.start_step;
  const bool sampled = model_->options().grid_mode == acoustic::GridMode::kSampled;
  if (sampled && !frozen_) {
    acoustic::GridSampler& grid = scenes_.front().grid;  // joint: one scene
    if (audio_step) {
      grid->update(field_query());
    } else {
      // No audio loss this step: the same cell values, without building a graph nobody uses.
      torch::NoGradGuard no_grad;
      grid->update(field_query());
    }
  }
  if (!audio_step) return {};

  const int64_t B = config_.audio.batch_size, T = scenes_.front().rirs->max_len;
  const double decay_weight = config_.audio.decay_weight;
  const int64_t D = decay_weight > 0 ? std::min<int64_t>(config_.audio.decay_rirs, n_train_) : 0;
  auto [pos, frame] = sample_slices(ctx.gen, D);
  // Data-parallel: this rank's rows of the global batch of B slices; the D whole RIRs of the
  // energy-decay loss are the same on every rank (their mean gradient is theirs).
  const int64_t Bl = ctx.shard.count(B);
  if (!ctx.shard.whole()) {
    const int64_t b0 = ctx.shard.begin(B);
    pos = torch::cat({pos.narrow(0, b0, Bl), pos.slice(0, B)});
    frame = torch::cat({frame.narrow(0, b0, Bl), frame.slice(0, B)});
  }
  torch::Tensor pred, gt;  // [Bl + D·T, C, F]
  if (scenes_.size() == 1) {
    const Scene& sc = scenes_.front();
    const data::RirSet& rirs = *sc.rirs;
    const torch::Tensor rir = torch::tensor(sc.train_rirs, torch::kInt64).index_select(0, pos);
    if (!batch_.defined() || batch_.size(0) != rir.size(0))
      batch_ = torch::empty({rir.size(0), rirs.channels, rirs.n_freq}, torch::kFloat32);
    rirs.gather_into(rir, frame, batch_);
    gt = batch_.to(device_);
    // Metres: the model normalises them by the audio box for the position encodings and takes
    // the relative geometry from the metres themselves (nacf_input).
    const torch::Tensor mic = rirs.mic_positions.index_select(0, rir);
    const torch::Tensor src = rirs.source_positions.index_select(0, rir);
    const torch::Tensor rot = rirs.rots.index_select(0, rir);
    pred = model_->forward(sc.grid->grid(), frame.to(device_), mic.to(device_), src.to(device_),
                           rot.to(device_));
  } else {
    std::tie(pred, gt) = forward_scenes(pos, frame, Bl);
  }
  {
    // Over the whole global batch, so every rank stops at the same step.
    const torch::Tensor own = pred.slice(0, 0, Bl).detach();
    const double edge = 0.999 * model_->options().nacf.output_scale;
    torch::Tensor counts = torch::stack({(own.abs() >= edge).sum().to(torch::kFloat64),
                                         torch::tensor(double(own.numel()), torch::kFloat64)});
    if (ctx.dist) ctx.dist->sum(counts);
    const double share = counts[0].item<double>() / std::max(1.0, counts[1].item<double>());
    ctx.metrics["audio_saturated"] = share;
    if (saturation_.saturated(share)) {
      char msg[240];
      std::snprintf(msg, sizeof msg,
                    "step %lld: the acoustic field's outputs are saturated (%.1f %% of the batch "
                    "at +-%g for %lld audio steps in a row); its tanh has no gradient there, so "
                    "it has stopped learning",
                    static_cast<long long>(ctx.step), 100.0 * share,
                    model_->options().nacf.output_scale,
                    static_cast<long long>(saturation_.patience));
      throw DivergedError(msg);
    }
  }
  acoustic::AudioLossOptions loss_options;
  loss_options.criterion = *acoustic::parse_audio_criterion(config_.audio.loss);  // validated
  const acoustic::AudioLossTerms terms =
      ctx.dist
          ? acoustic::spectral_loss_sharded(
                pred.slice(0, 0, Bl), gt.slice(0, 0, Bl),
                [&](torch::Tensor& t) { ctx.dist->sum(t); }, ctx.shard.world_size, loss_options)
          : acoustic::spectral_loss(pred.slice(0, 0, Bl), gt.slice(0, 0, Bl), loss_options);
  ctx.metrics["audio_sl"] = terms.sl.item<double>();
  LossDict out{{"audio_sc_loss", terms.sc_loss}, {"audio_mag_loss", terms.mag_loss}};
  if (D > 0) {
    // [D·T, C, F] → [D, C, F, T]
    auto whole_rirs = [&](const torch::Tensor& x) {
      return x.slice(0, Bl).view({D, T, x.size(1), x.size(2)}).permute({0, 2, 3, 1});
    };
    const acoustic::AudioLossOptions lo;
    const torch::Tensor decay = acoustic::energy_decay_loss(whole_rirs(pred), whole_rirs(gt),
                                                            lo.decay_eps, lo.decay_floor_db);
    ctx.metrics["audio_decay"] = decay.item<double>();
    out["audio_decay_loss"] = lo.loss_factor * decay_weight * decay;
  }
  return out;
}

void AudioBranch::after_step(int64_t step, int64_t total_steps) {
  const double share = config_.audio.average_fraction;
  if (share <= 0 || step <= config_.audio.start_step) return;
  const int64_t audio_steps = total_steps - std::max<int64_t>(0, config_.audio.start_step + 1);
  // (− 1e-9: a share × steps that is whole in decimals, 0.1 × 30, must not round up to 4.)
  const auto window =
      std::max<int64_t>(1, static_cast<int64_t>(std::ceil(share * audio_steps - 1e-9)));
  if (step < total_steps - window) {
    averaged_steps_ = 0;
    return;
  }
  torch::NoGradGuard no_grad;
  if (!average_) {
    average_ = acoustic::AcousticModel(model_->options());  // its weights are overwritten
    average_->to(device_);
  }
  const std::vector<torch::Tensor> params = model_->parameters();
  std::vector<torch::Tensor> mean = average_->parameters();
  ++averaged_steps_;
  for (size_t i = 0; i < params.size(); ++i) {
    if (averaged_steps_ == 1)
      mean[i].copy_(params[i]);
    else
      mean[i].add_(params[i] - mean[i], 1.0 / static_cast<double>(averaged_steps_));
  }
}

void AudioBranch::save(torch::serialize::OutputArchive& archive) {
  torch::serialize::OutputArchive m;
  model_->save(m);
  archive.write("model", m);
  if (averaged_steps_ > 0) {
    {
      torch::NoGradGuard no_grad;
      const std::vector<torch::Tensor> from = model_->buffers();  // BatchNorm statistics
      std::vector<torch::Tensor> to = average_->buffers();
      for (size_t i = 0; i < from.size(); ++i) to[i].copy_(from[i]);
    }
    torch::serialize::OutputArchive a;
    average_->save(a);
    archive.write("model_average", a);
    archive.write("average_steps", torch::tensor(averaged_steps_, torch::kInt64));
  }
  for (size_t s = 0; s < scenes_.size(); ++s) {
    // The step's backward is done: cut the fresh cells' autograd history so that only values are
    // serialised (the next update detaches the grid anyway).
    const_cast<torch::Tensor&>(scenes_[s].grid->grid()).detach_();
    torch::serialize::OutputArchive g;
    scenes_[s].grid->save(g);
    archive.write(infer::scene_key("grid", s), g);
  }
  archive.write("perm", perm_.defined() ? perm_ : torch::empty({0}, torch::kInt64));
  archive.write("cursor", torch::tensor(cursor_, torch::kInt64));
  for (size_t s = 0; s < scenes_.size(); ++s) {
    archive.write(infer::scene_key("manifest", s),
                  c10::IValue(infer::make_audio_manifest(*scenes_[s].rirs).dump()));
    archive.write(infer::scene_key("train_rirs", s),
                  torch::tensor(scenes_[s].train_rirs, torch::kInt64));
  }
  if (scenes_.size() > 1)
    archive.write("num_scenes", torch::tensor(static_cast<int64_t>(scenes_.size()), torch::kInt64));
}

void AudioBranch::load(torch::serialize::InputArchive& archive, const std::string& where) {
  torch::Tensor n_scenes;
  const int64_t stored = archive.try_read("num_scenes", n_scenes) ? n_scenes.item<int64_t>() : 1;
  require(stored == static_cast<int64_t>(scenes_.size()),
          where + ": checkpoint was trained on " + std::to_string(stored) +
              " scene(s), this run has " + std::to_string(scenes_.size()) +
              "; resume with the run's own --data");
  for (size_t s = 0; s < scenes_.size(); ++s) {
    c10::IValue manifest;
    require(archive.try_read(infer::scene_key("manifest", s), manifest) && manifest.isString(),
            where + ": checkpoint has no audio data manifest; it was not written by neraf train");
    infer::check_audio_manifest(nlohmann::json::parse(manifest.toStringRef()), *scenes_[s].rirs,
                                where);
  }
  torch::serialize::InputArchive m;
  archive.read("model", m);
  infer::load_module(*model_, m, where);
  model_->to(device_);
  torch::serialize::InputArchive a;
  averaged_steps_ = 0;
  if (archive.try_read("model_average", a)) {
    if (!average_) average_ = acoustic::AcousticModel(model_->options());
    infer::load_module(*average_, a, where);
    average_->to(device_);
    torch::Tensor n;
    archive.read("average_steps", n);
    averaged_steps_ = n.item<int64_t>();
  }
  for (size_t s = 0; s < scenes_.size(); ++s) {
    Scene& sc = scenes_[s];
    torch::serialize::InputArchive g;
    archive.read(infer::scene_key("grid", s), g);
    infer::load_module(*sc.grid, g, where);
    sc.grid->to(device_);
    torch::Tensor subset;
    archive.read(infer::scene_key("train_rirs", s), subset);
    require(subset.numel() == static_cast<int64_t>(sc.train_rirs.size()) &&
                std::equal(sc.train_rirs.begin(), sc.train_rirs.end(), subset.data_ptr<int64_t>()),
            where +
                ": checkpoint was trained on another subset of the RIRs (--audio-fraction or "
                "--seed differ); use a new --out folder");
  }
  torch::Tensor perm, cursor;
  archive.read("perm", perm);
  archive.read("cursor", cursor);
  require(perm.numel() == 0 || perm.numel() == n_slices_,
          where + ": checkpoint drew its batches from " + std::to_string(perm.numel()) +
              " (RIR, frame) slices, this run has " + std::to_string(n_slices_) +
              " (other RIRs or frames per RIR); use a new --out folder");
  perm_ = perm.numel() > 0 ? perm : torch::Tensor();
  cursor_ = cursor.item<int64_t>();
}

}  // namespace neraf::train
