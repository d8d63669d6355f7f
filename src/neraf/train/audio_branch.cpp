#include "neraf/train/audio_branch.h"

#include <ATen/CPUGeneratorImpl.h>

#include <algorithm>
#include <cmath>

#include "neraf/acoustic/calibration.h"
#include "neraf/acoustic/losses.h"
#include "neraf/infer/audio_run.h"
#include "neraf/infer/checkpoint.h"
#include "neraf/metrics/room_acoustics.h"
#include "neraf/train/distributed.h"
#include "neraf/util/error.h"

namespace neraf::train {

using infer::TrainConfig;

AudioBranch::AudioBranch(const TrainConfig& config, const data::RirSet& rirs,
                         nerf::NerfactoModel field, bool frozen_field, torch::Device device)
    : config_(config),
      rirs_(rirs),
      field_(std::move(field)),
      frozen_(frozen_field),
      device_(device) {
  require(rirs_.has_features(), "dataset: the RIR features were not loaded");
  require(!rirs_.train.empty(),
          "dataset: the audio train split is empty; the acoustic field "
          "needs training RIRs");
  const acoustic::AcousticModelOptions opts = infer::audio_model_options(
      config_, rirs_.channels, rirs_.n_freq, rirs_.max_len, rirs_.audio_aabb);
  model_ = acoustic::AcousticModel(opts);
  model_->to(device_);
  grid_ = acoustic::GridSampler(opts.grid);
  grid_->to(device_);
  train_rirs_ = infer::audio_train_subset(rirs_, config_.audio.fraction, config_.seed);
  if (frozen_ && opts.grid_mode == acoustic::GridMode::kSampled) {
    // The paper's separate training: the field is final, so the whole grid is filled once.
    field_->eval();
    grid_->refresh_all(field_query());
  }
}

acoustic::FieldQueryFn AudioBranch::field_query() {
  nerf::NerfactoModel field = field_;
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
    for (auto& p : field_->field_parameters()) params.push_back(p);
  return {{"audio_fields", params, config_.audio.schedule}};
}

void AudioBranch::set_training(bool training) {
  model_->train(training);
  grid_->train(training);
}

std::pair<torch::Tensor, torch::Tensor> AudioBranch::sample_slices(at::Generator& gen, int64_t D) {
  const int64_t T = rirs_.max_len;
  const int64_t n = static_cast<int64_t>(train_rirs_.size()) * T;
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
  const torch::Tensor slice = torch::tensor(picks, torch::kInt64);
  torch::Tensor local = torch::div(slice, T, "floor");  // position in train_rirs_
  torch::Tensor frame = slice - local * T;
  // Early share: random train RIRs, frames in [0, early_frames).
  const int64_t n_rirs = static_cast<int64_t>(train_rirs_.size());
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
  return {torch::tensor(train_rirs_, torch::kInt64).index_select(0, local), frame};
}

LossDict AudioBranch::losses(StepContext& ctx) {
  const bool audio_step = ctx.step > config_.audio.start_step;
  const bool sampled = model_->options().grid_mode == acoustic::GridMode::kSampled;
  if (sampled && !frozen_) {
    if (audio_step) {
      grid_->update(field_query());
    } else {
      // No audio loss this step: the same cell values, without building a graph nobody uses.
      torch::NoGradGuard no_grad;
      grid_->update(field_query());
    }
  }
  if (!audio_step) return {};

  const int64_t B = config_.audio.batch_size, T = rirs_.max_len;
  const double decay_weight = config_.audio.decay_weight;
  const int64_t D = decay_weight > 0 ? std::min<int64_t>(config_.audio.decay_rirs,
                                                         static_cast<int64_t>(train_rirs_.size()))
                                     : 0;
  auto [rir, frame] = sample_slices(ctx.gen, D);
  // Data-parallel: this rank's rows of the global batch of B slices; the D whole RIRs of the
  // energy-decay loss are the same on every rank (their mean gradient is theirs).
  const int64_t Bl = ctx.shard.count(B);
  if (!ctx.shard.whole()) {
    const int64_t b0 = ctx.shard.begin(B);
    rir = torch::cat({rir.narrow(0, b0, Bl), rir.slice(0, B)});
    frame = torch::cat({frame.narrow(0, b0, Bl), frame.slice(0, B)});
  }
  if (!batch_.defined() || batch_.size(0) != rir.size(0))
    batch_ = torch::empty({rir.size(0), rirs_.channels, rirs_.n_freq}, torch::kFloat32);
  rirs_.gather_into(rir, frame, batch_);
  const torch::Tensor gt = batch_.to(device_);  // [B + D·T, C, F]
  // Metres: the model normalises them by the audio box for the position encodings and takes the
  // relative geometry from the metres themselves (nacf_input).
  const torch::Tensor mic = rirs_.mic_positions.index_select(0, rir);
  const torch::Tensor src = rirs_.source_positions.index_select(0, rir);
  const torch::Tensor rot = rirs_.rots.index_select(0, rir);
  const torch::Tensor pred = model_->forward(grid_->grid(), frame.to(device_), mic.to(device_),
                                             src.to(device_), rot.to(device_));  // [Bl + D·T, C, F]
  const acoustic::AudioLossTerms terms =
      ctx.dist ? acoustic::sc_slmse_loss_sharded(
                     pred.slice(0, 0, Bl), gt.slice(0, 0, Bl),
                     [&](torch::Tensor& t) { ctx.dist->sum(t); }, ctx.shard.world_size)
               : acoustic::sc_slmse_loss(pred.slice(0, 0, Bl), gt.slice(0, 0, Bl));
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

void AudioBranch::save(torch::serialize::OutputArchive& archive) {
  torch::serialize::OutputArchive m, g;
  model_->save(m);
  archive.write("model", m);
  // The step's backward is done: cut the fresh cells' autograd history so that only values are
  // serialised (the next update detaches the grid anyway).
  const_cast<torch::Tensor&>(grid_->grid()).detach_();
  grid_->save(g);
  archive.write("grid", g);
  archive.write("perm", perm_.defined() ? perm_ : torch::empty({0}, torch::kInt64));
  archive.write("cursor", torch::tensor(cursor_, torch::kInt64));
  archive.write("manifest", c10::IValue(infer::make_audio_manifest(rirs_).dump()));
  archive.write("train_rirs", torch::tensor(train_rirs_, torch::kInt64));
}

void AudioBranch::load(torch::serialize::InputArchive& archive, const std::string& where) {
  c10::IValue manifest;
  require(archive.try_read("manifest", manifest) && manifest.isString(),
          where + ": checkpoint has no audio data manifest; it was not written by neraf train");
  infer::check_audio_manifest(nlohmann::json::parse(manifest.toStringRef()), rirs_, where);
  torch::serialize::InputArchive m, g;
  archive.read("model", m);
  infer::load_module(*model_, m, where);
  model_->to(device_);
  archive.read("grid", g);
  infer::load_module(*grid_, g, where);
  grid_->to(device_);
  torch::Tensor perm, cursor, subset;
  archive.read("perm", perm);
  archive.read("cursor", cursor);
  archive.read("train_rirs", subset);
  require(subset.numel() == static_cast<int64_t>(train_rirs_.size()) &&
              std::equal(train_rirs_.begin(), train_rirs_.end(), subset.data_ptr<int64_t>()),
          where +
              ": checkpoint was trained on another subset of the RIRs (--audio-fraction or "
              "--seed differ); use a new --out folder");
  perm_ = perm.numel() > 0 ? perm : torch::Tensor();
  cursor_ = cursor.item<int64_t>();
}

}  // namespace neraf::train
