#include "neraf/train/trainer.h"

#include <ATen/CPUGeneratorImpl.h>

#include <cmath>
#include <mutex>
#include <unordered_set>

#include "neraf/infer/checkpoint.h"
#include "neraf/infer/run.h"
#include "neraf/nerf/rays.h"
#include "neraf/nerf/samplers.h"
#include "neraf/train/audio_branch.h"
#include "neraf/train/distributed.h"
#include "neraf/train/lr_schedule.h"
#include "neraf/util/error.h"

namespace neraf::train {

using infer::LoadedRun;
using infer::Modality;
using infer::TrainConfig;

// ---------------------------------------------------------------------------------------------
// VisionBranch

VisionBranch::VisionBranch(const TrainConfig& config, const data::ImageSplit& train,
                           torch::Device device)
    : config_(config), device_(device) {
  require(train.size() >= 1, "dataset: the train split is empty; add train_ frames");
  require(train.images.defined() && train.images.dim() == 4 && train.images.size(3) == 3 &&
              train.images.scalar_type() == torch::kUInt8,
          "dataset: training images were not loaded (expected [N, H, W, 3] uint8 pixels)");
  require(static_cast<int64_t>(train.intrinsics.size()) == train.size(),
          "dataset: one intrinsics entry per training frame is required");
  num_images_ = train.images.size(0);
  height_ = train.images.size(1);
  width_ = train.images.size(2);
  pixels_ = train.images.reshape({-1, 3}).to(device);
  c2w_ = train.camera_to_world.to(torch::kFloat32).to(device);
  std::vector<torch::Tensor> rows;
  for (const auto& k : train.intrinsics) rows.push_back(nerf::intrinsics_row(k));
  intr_ = torch::stack(rows).to(device);
  model_ = nerf::NerfactoModel(config.model, num_images_, config.seed);
  model_->to(device);
  model_->train();
}

std::vector<ParamGroup> VisionBranch::param_groups() {
  return {{"proposal_networks", model_->proposal_parameters(), config_.proposal_networks},
          {"fields", model_->field_parameters(), config_.fields},
          {"camera_opt", model_->camera_parameters(), config_.camera_opt}};
}

void VisionBranch::set_training(bool training) { model_->train(training); }

LossDict VisionBranch::losses(StepContext& ctx) {
  const int64_t R = config_.rays_per_batch;
  const int64_t per_image = height_ * width_;
  // Uniform random pixels over all training images (nerfstudio's PixelSampler).
  // Data-parallel: the global batch's pixels are drawn, this rank keeps its rows (and their
  // jitter, nerf::JitterRows), so the ranks together see exactly one process's batch.
  torch::Tensor idx = torch::randint(0, num_images_ * per_image, {R}, ctx.gen, torch::kInt64);
  nerf::JitterRows rows;
  if (!ctx.shard.whole()) {
    rows = {R, ctx.shard.begin(R)};
    idx = idx.narrow(0, rows.begin, ctx.shard.count(R));
  }
  idx = idx.to(device_);
  const torch::Tensor img = torch::div(idx, per_image, "floor");
  const torch::Tensor rem = idx - img * per_image;
  const torch::Tensor row = torch::div(rem, width_, "floor");
  const torch::Tensor col = rem - row * width_;
  const torch::Tensor gt = pixels_.index_select(0, idx).to(torch::kFloat32) / 255.0;  // [R, 3]

  nerf::RayBundle rays =
      nerf::rays_from_pixels(c2w_.index_select(0, img), intr_.index_select(0, img),
                             col.to(torch::kFloat32) + 0.5, row.to(torch::kFloat32) + 0.5);
  rays.camera_indices = img;

  const auto& sc = config_.model.sampler;
  const nerf::ProposalUpdate pu = nerf::proposal_update(
      ctx.step, steps_since_update_, sc.proposal_update_every, sc.proposal_warmup);
  steps_since_update_ = pu.steps_since_update;
  const double anneal =
      sc.use_proposal_weight_anneal
          ? nerf::proposal_weight_anneal(ctx.step, sc.proposal_weights_anneal_slope,
                                         sc.proposal_weights_anneal_max_num_iters)
          : 1.0;
  const nerf::ModelOutputs out = model_->forward(rays, {pu.update, anneal, &ctx.gen, rows});
  LossDict l = model_->losses(out, gt);
  const double mse = l.at("rgb_loss").item<double>();
  ctx.metrics["psnr"] = -10.0 * std::log10(std::max(mse, 1e-12));
  return l;
}

void VisionBranch::save(torch::serialize::OutputArchive& archive) {
  torch::serialize::OutputArchive model_archive;
  model_->save(model_archive);
  archive.write("model", model_archive);
  archive.write("steps_since_update", torch::tensor(steps_since_update_, torch::kInt64));
}

void VisionBranch::load(torch::serialize::InputArchive& archive, const std::string& where) {
  torch::serialize::InputArchive model_archive;
  archive.read("model", model_archive);
  infer::load_module(*model_, model_archive, where);
  model_->to(device_);
  torch::Tensor s;
  archive.read("steps_since_update", s);
  steps_since_update_ = s.item<int64_t>();
}

// ---------------------------------------------------------------------------------------------
// Trainer

namespace {

// The ranks' means of the step's loss values and metrics (one small all-reduce); the metrics are
// replaced in place, the losses returned by name. Every rank has the same names (the branches
// and their schedules are deterministic).
std::map<std::string, double> mean_over_ranks(const LossDict& losses,
                                              std::map<std::string, double>& metrics,
                                              Distributed& dist) {
  std::vector<double> values;
  for (const auto& [k, v] : losses) values.push_back(v.detach().item<double>());
  for (const auto& [k, v] : metrics) values.push_back(v);
  std::map<std::string, double> out;
  if (values.empty()) return out;
  torch::Tensor t = torch::tensor(values, torch::kFloat64);  // [n_losses + n_metrics]
  dist.sum(t);
  t.div_(dist.world_size());
  const double* p = t.data_ptr<double>();
  for (const auto& [k, v] : losses) out[k] = *p++;
  for (auto& [k, v] : metrics) v = *p++;
  return out;
}

}  // namespace

void Trainer::set_distributed(Distributed* dist) { dist_ = dist; }

void Trainer::broadcast_parameters() {
  if (!dist_) return;
  if (groups_.empty()) build_optimizers();
  std::unordered_set<const void*> seen;
  std::vector<torch::Tensor> params;
  for (const auto& g : groups_)
    for (const auto& p : g.params)
      if (seen.insert(p.unsafeGetTensorImpl()).second) params.push_back(p);
  dist_->broadcast(params);
}

Trainer::Trainer(TrainConfig config, torch::Device device)
    : config_(std::move(config)),
      device_(device),
      gen_(at::make_generator<at::CPUGeneratorImpl>(config_.seed)) {}

void Trainer::add_branch(std::unique_ptr<Branch> branch) {
  TORCH_CHECK(groups_.empty(), "add_branch: optimizers were already built");
  branches_.push_back(std::move(branch));
}

void Trainer::build_optimizers() {
  for (auto& b : branches_)
    for (auto& g : b->param_groups()) {
      if (g.params.empty()) continue;  // e.g. camera_opt when the pose optimizer is off
      Group group;
      group.name = g.name;
      group.schedule = g.schedule;
      group.params = g.params;
      group.optimizer = std::make_unique<torch::optim::Adam>(
          g.params, torch::optim::AdamOptions(g.schedule.lr).eps(g.schedule.eps));
      groups_.push_back(std::move(group));
    }
}

VisionBranch* Trainer::vision() { return dynamic_cast<VisionBranch*>(branch("vision")); }

Branch* Trainer::branch(const std::string& name) {
  for (auto& b : branches_)
    if (b->name() == name) return b.get();
  return nullptr;
}

double Trainer::group_lr(const std::string& name) const {
  for (const auto& g : groups_)
    if (g.name == name) return learning_rate(g.schedule, step_);
  return 0.0;
}

StepResult Trainer::step() {
  if (groups_.empty()) build_optimizers();
  for (auto& g : groups_) {
    const double lr = learning_rate(g.schedule, step_);
    for (auto& pg : g.optimizer->param_groups())
      static_cast<torch::optim::AdamOptions&>(pg.options()).lr(lr);
  }
  // Gradients are reset to "none" (PyTorch's zero_grad(set_to_none=True)), so parameters that
  // take no part in this step's graph (the proposal nets between updates) are skipped by Adam
  // instead of being moved by their decaying moments.
  for (auto& g : groups_)
    for (auto& p : g.params) p.mutable_grad() = torch::Tensor();

  StepResult result;
  StepContext ctx{step_, gen_, result.metrics};
  if (dist_) {
    ctx.shard = {dist_->rank(), dist_->world_size()};
    ctx.dist = dist_;
  }
  LossDict all;
  for (auto& b : branches_) {
    for (auto& [k, v] : b->losses(ctx)) {
      TORCH_CHECK(!all.count(k), "two branches report the loss '", k, "'");
      all[k] = v;
    }
    result.rays += b->rays_per_step();
  }
  // Distributed: the values every rank reports (and checks) are the ranks' means.
  std::map<std::string, double> reported;
  if (dist_) reported = mean_over_ranks(all, result.metrics, *dist_);
  if (!all.empty()) {
    torch::Tensor total = torch::zeros({}, all.begin()->second.options());
    for (const auto& [k, v] : all) {
      total = total + v;
      result.losses[k] = dist_ ? reported.at(k) : v.item<double>();
      if (!std::isfinite(result.losses[k]))
        throw DivergedError("step " + std::to_string(step_ + 1) + ": the loss term '" + k +
                            "' is " + (std::isnan(result.losses[k]) ? "NaN" : "infinite") +
                            " (training diverged)");
    }
    if (dist_) {
      std::vector<torch::Tensor> params;
      for (const auto& g : groups_) params.insert(params.end(), g.params.begin(), g.params.end());
      dist_->backward_and_average(total, params);
    } else if (total.requires_grad()) {
      total.backward();
    }
    for (auto& g : groups_) g.optimizer->step();
    for (auto& b : branches_) b->after_step(step_, config_.steps);
    if (dist_) {
      result.loss = 0;
      for (const auto& [k, v] : result.losses) result.loss += v;
    } else {
      result.loss = total.item<double>();
    }
  }
  result.step = ++step_;
  return result;
}

void Trainer::save_checkpoint(const std::string& path) {
  if (groups_.empty()) build_optimizers();
  for (const auto& g : groups_)
    for (const auto& p : g.params)
      if (!torch::isfinite(p).all().item<bool>())
        throw DivergedError("step " + std::to_string(step_) + ": weights of '" + g.name +
                            "' are not finite (training diverged); not saving " + path);
  torch::serialize::OutputArchive a;
  a.write("format", c10::IValue(std::string(infer::kCheckpointFormat)));
  a.write("config", c10::IValue(to_json(config_).dump()));
  a.write("step", torch::tensor(step_, torch::kInt64));
  {
    std::lock_guard<std::mutex> lock(gen_.mutex());
    a.write("rng", gen_.get_state());
  }
  for (auto& b : branches_) {
    torch::serialize::OutputArchive sub;
    b->save(sub);
    a.write("branch_" + b->name(), sub);
  }
  for (auto& g : groups_) {
    torch::serialize::OutputArchive sub;
    g.optimizer->save(sub);
    a.write("optim_" + g.name, sub);
  }
  infer::save_archive(a, path);
}

void Trainer::load_checkpoint(const std::string& path) {
  torch::serialize::InputArchive a;
  infer::load_archive(a, path);
  load_state(a, path);
}

void Trainer::load_checkpoint_bytes(const std::string& bytes, const std::string& path) {
  torch::serialize::InputArchive a;
  infer::load_archive_bytes(a, bytes, path);
  load_state(a, path);
}

void Trainer::load_state(torch::serialize::InputArchive& a, const std::string& path) {
  if (groups_.empty()) build_optimizers();
  infer::check_checkpoint_header(a, config_, path);
  try {
    torch::Tensor step, rng;
    a.read("step", step);
    a.read("rng", rng);
    for (auto& b : branches_) {
      torch::serialize::InputArchive sub;
      a.read("branch_" + b->name(), sub);
      b->load(sub, path);
    }
    for (auto& g : groups_) {
      torch::serialize::InputArchive sub;
      a.read("optim_" + g.name, sub);
      g.optimizer->load(sub);
    }
    step_ = step.item<int64_t>();
    std::lock_guard<std::mutex> lock(gen_.mutex());
    gen_.set_state(rng);
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    what = what.substr(0, what.find('\n'));
    throw Error(path + ": checkpoint does not match this model (" + what +
                "); it was written by another version or for another dataset");
  }
}

namespace {

// The frozen field's frame, from its run's manifest (read only when the grid is read per query).
acoustic::WorldToField world_to_field_of(const TrainConfig& config, const LoadedRun& vision) {
  if (config.audio.grid_features == "global") return acoustic::kIdentityWorldToField;
  return infer::world_to_field(vision.manifest, vision.run_dir + "/data.json");
}

}  // namespace

std::unique_ptr<Trainer> make_trainer(const TrainConfig& config, const data::ImageSet* images,
                                      torch::Device device, const data::RirSet* rirs) {
  validate(config, "config");
  auto trainer = std::make_unique<Trainer>(config, device);
  if (config.modality != Modality::vision)
    require(rirs != nullptr,
            "--data: an audio/joint run needs the scene's RIRs (SoundSpaces or "
            "RAF layout)");
  if (config.modality == Modality::audio) {
    // The paper's separate training: the acoustic field on the frozen grid of a vision run.
    require(!config.audio.vision_run.empty(),
            "--vision-run: required with --modality audio (a finished vision or joint run)");
    LoadedRun vision = infer::load_run(config.audio.vision_run, device);
    for (auto& p : vision.model->parameters()) p.set_requires_grad(false);
    trainer->add_branch(std::make_unique<AudioBranch>(config, *rirs, vision.model,
                                                      world_to_field_of(config, vision),
                                                      /*frozen_field=*/true, device));
    return trainer;
  }
  require(images != nullptr, "--data: a vision run needs posed images (transforms.json)");
  trainer->add_branch(std::make_unique<VisionBranch>(config, images->train, device));
  if (config.modality == Modality::joint)
    trainer->add_branch(std::make_unique<AudioBranch>(config, *rirs, trainer->vision()->model(),
                                                      infer::world_to_field(*images),
                                                      /*frozen_field=*/false, device));
  return trainer;
}

std::unique_ptr<Trainer> make_multiscene_trainer(const TrainConfig& config,
                                                 const std::vector<const data::RirSet*>& scenes,
                                                 torch::Device device,
                                                 const std::vector<int64_t>& scene_frames) {
  validate(config, "config");
  require(config.modality == Modality::audio && config.audio.vision_runs.size() == scenes.size(),
          "multi-scene: one --vision-run per --data (--modality audio)");
  auto trainer = std::make_unique<Trainer>(config, device);
  std::vector<nerf::NerfactoModel> fields;
  std::vector<acoustic::WorldToField> maps;
  for (const std::string& dir : config.audio.vision_runs) {
    LoadedRun vision = infer::load_run(dir, device);
    for (auto& p : vision.model->parameters()) p.set_requires_grad(false);
    fields.push_back(vision.model);
    maps.push_back(world_to_field_of(config, vision));
  }
  trainer->add_branch(std::make_unique<AudioBranch>(config, scenes, fields, maps,
                                                    /*frozen_field=*/true, device, scene_frames));
  return trainer;
}

}  // namespace neraf::train
