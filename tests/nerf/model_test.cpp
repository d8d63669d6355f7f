#include <ATen/CPUGeneratorImpl.h>
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cstdio>

#include "neraf/nerf/nerfacto_model.h"
#include "neraf/nerf/samplers.h"

using namespace neraf::nerf;

namespace {

// A small model so the tests stay fast.
ModelConfig tiny_config(Precision p = Precision::fp32) {
  ModelConfig c = model_preset("cpu");
  c.field.grid = {8, 2, 12, 16, 128};
  c.proposal_nets = {ProposalNetConfig{{4, 2, 10, 16, 64}, 2, 16},
                     ProposalNetConfig{{4, 2, 10, 16, 128}, 2, 16}};
  c.sampler.proposal_samples = {32, 16};
  c.sampler.nerf_samples = 8;
  c.sampler.far_plane = 10.0;
  c.camera_opt.mode = CameraOptMode::SO3xR3;
  c.precision = p;
  return c;
}

RayBundle random_rays(int64_t R, int64_t num_cams, uint64_t seed) {
  auto gen = at::make_generator<at::CPUGeneratorImpl>(seed);
  RayBundle r;
  r.origins = torch::rand({R, 3}, gen) * 0.5 - 0.25;
  auto d = torch::rand({R, 3}, gen) - 0.5;
  r.directions = d / d.norm(2, 1, true);
  r.camera_indices = torch::randint(0, num_cams, {R}, gen);
  return r;
}

}  // namespace

TEST(NerfactoField, MlpsAreBiasFreeWithNerfactoSizes) {
  FieldConfig fc;  // paper sizes
  NerfactoField f(fc, 3, Precision::fp32, 1);
  const auto& wb = f->mlp_base->weights();
  ASSERT_EQ(wb.size(), 2u);
  EXPECT_EQ(wb[0].sizes(), (std::vector<int64_t>{64, 32}));
  EXPECT_EQ(wb[1].sizes(), (std::vector<int64_t>{16, 64}));
  const auto& wh = f->mlp_head->weights();
  ASSERT_EQ(wh.size(), 3u);
  EXPECT_EQ(wh[0].sizes(), (std::vector<int64_t>{64, 63}));
  EXPECT_EQ(wh[2].sizes(), (std::vector<int64_t>{3, 64}));
  int64_t n = 0;
  for (const auto& p : f->parameters()) n += p.numel();
  const int64_t mlp = 32 * 64 + 64 * 16 + 63 * 64 + 64 * 64 + 64 * 3;
  EXPECT_EQ(n, f->grid->layout().num_parameters() + mlp + 3 * 32);
  // Xavier-uniform bound √(6/(fan_in + fan_out)).
  EXPECT_LE(wb[0].abs().max().item<float>(), std::sqrt(6.0f / 96.0f));
}

TEST(NerfactoField, QueryInterface) {
  NerfactoField f(tiny_config().field, 4, Precision::fp32, 3);
  const auto u = torch::tensor(
      {{0.5f, 0.5f, 0.5f}, {0.1f, 0.9f, 0.3f}, {0.0f, 0.5f, 0.5f}, {1.2f, 0.5f, 0.5f}});
  auto dirs = torch::tensor({{0.f, 0.f, 1.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}, {0.f, 0.f, -1.f}});
  const FieldQuery q = f->query(u, dirs, torch::tensor({-1}, torch::kInt64));
  ASSERT_EQ(q.density.sizes(), (std::vector<int64_t>{4}));
  ASSERT_EQ(q.rgb.sizes(), (std::vector<int64_t>{4, 3}));
  EXPECT_GT(q.density[0].item<float>(), 0.0f);
  EXPECT_EQ(q.density[2].item<float>(), 0.0f);  // on the cube's boundary: outside
  EXPECT_EQ(q.density[3].item<float>(), 0.0f);
  EXPECT_TRUE(((q.rgb > 0) & (q.rgb < 1)).all().item<bool>());
  // Initial density ≈ average_init_density · exp(small) = 0.01.
  EXPECT_NEAR(q.density[0].item<float>(), 0.01f, 0.005f);
  // Per-point appearance ids; −1 is the mean embedding.
  const FieldQuery q2 = f->query(u, dirs, torch::tensor({0, 1, 2, -1}, torch::kInt64));
  EXPECT_TRUE(torch::allclose(q2.rgb[3], q.rgb[3]));
  EXPECT_TRUE(torch::equal(q2.density, q.density));  // density is appearance independent
  // With autograd: the table gets gradients.
  (q.density.sum() + q.rgb.sum()).backward();
  ASSERT_TRUE(f->grid->table.grad().defined());
  EXPECT_GT(f->grid->table.grad().abs().sum().item<float>(), 0.0f);
  // And without.
  torch::NoGradGuard ng;
  const FieldQuery q3 = f->query(u, dirs, torch::tensor({-1}, torch::kInt64));
  EXPECT_FALSE(q3.density.requires_grad());
  EXPECT_TRUE(torch::equal(q3.rgb, q.rgb.detach()));
}

TEST(NerfactoField, AlongRaysEqualsPointQueries) {
  NerfactoField f(tiny_config().field, 2, Precision::fp32, 5);
  torch::NoGradGuard ng;
  const auto pos = torch::rand({3, 4, 3}) * 4 - 2;
  auto d = torch::rand({3, 3}) - 0.5;
  d = d / d.norm(2, 1, true);
  const auto ids = torch::tensor({0, 1, -1}, torch::kInt64);
  const auto out = f->forward(pos, d, ids);
  const auto u = (scene_contract(pos.reshape({12, 3})) + 2) / 4;
  const FieldQuery q = f->query(u, d.repeat_interleave(4, 0), ids.repeat_interleave(4, 0));
  EXPECT_TRUE(torch::allclose(out.density.reshape({12}), q.density, 1e-5, 1e-6));
  EXPECT_TRUE(torch::allclose(out.rgb.reshape({12, 3}), q.rgb, 1e-5, 1e-6));
}

TEST(NerfactoModel, TrainingForwardLossesAndGradients) {
  NerfactoModel m(tiny_config(), 3, 1);
  m->train();
  auto gen = at::make_generator<at::CPUGeneratorImpl>(9);
  const RayBundle rays = random_rays(64, 3, 2);
  const ModelOutputs o = m->forward(rays, ForwardOptions{true, 0.5, &gen});
  ASSERT_EQ(o.rgb.sizes(), (std::vector<int64_t>{64, 3}));
  ASSERT_EQ(o.weights.size(), 3u);
  EXPECT_EQ(o.weights[0].size(1), 32);
  EXPECT_EQ(o.weights[1].size(1), 16);
  EXPECT_EQ(o.weights[2].size(1), 8);
  EXPECT_EQ(o.sdist[2].size(1), 9);
  for (const auto& t : o.tdist) {
    EXPECT_GE(t.min().item<float>(), 0.05f - 1e-6f);
    EXPECT_LE(t.max().item<float>(), 10.0f + 1e-4f);
  }
  const LossDict l = m->losses(o, torch::rand({64, 3}));
  for (const char* k : {"rgb_loss", "interlevel_loss", "distortion_loss", "camera_opt_regularizer"})
    ASSERT_TRUE(l.count(k)) << k;
  torch::Tensor total = torch::zeros({});
  for (const auto& [k, v] : l) total = total + v;
  total.backward();
  auto has_grad = [](const std::vector<torch::Tensor>& ps) {
    for (const auto& p : ps)
      if (!p.grad().defined()) return false;
    return true;
  };
  EXPECT_TRUE(has_grad(m->field_parameters()));
  EXPECT_TRUE(has_grad(m->proposal_parameters()));
  EXPECT_TRUE(has_grad(m->camera_parameters()));
  for (const auto& p : m->parameters()) {
    if (p.grad().defined()) EXPECT_TRUE(torch::isfinite(p.grad()).all().item<bool>());
  }
}

TEST(NerfactoModel, ProposalNetworksFrozenWhenNotUpdating) {
  NerfactoModel m(tiny_config(), 3, 1);
  m->train();
  auto gen = at::make_generator<at::CPUGeneratorImpl>(9);
  const ModelOutputs o = m->forward(random_rays(32, 3, 4), ForwardOptions{false, 1.0, &gen});
  const LossDict l = m->losses(o, torch::rand({32, 3}));
  EXPECT_FALSE(l.at("interlevel_loss").requires_grad());
  (l.at("rgb_loss") + l.at("distortion_loss")).backward();
  for (const auto& p : m->proposal_parameters()) EXPECT_FALSE(p.grad().defined());
  EXPECT_TRUE(m->field->grid->table.grad().defined());
}

TEST(NerfactoModel, EvalIsDeterministicAndClamped) {
  NerfactoModel m(tiny_config(), 3, 1);
  RayBundle rays = random_rays(100, 3, 5);
  rays.camera_indices = torch::Tensor();
  const ModelOutputs a = m->render(rays, 33);
  const ModelOutputs b = m->render(rays, 100);
  EXPECT_TRUE(torch::allclose(a.rgb, b.rgb, 1e-6, 1e-6));
  EXPECT_TRUE(torch::equal(a.depth, b.depth));
  EXPECT_GE(a.rgb.min().item<float>(), 0.0f);
  EXPECT_LE(a.rgb.max().item<float>(), 1.0f);
  EXPECT_EQ(a.depth.sizes(), (std::vector<int64_t>{100}));
  EXPECT_TRUE(m->is_training());  // render() restores the mode
}

TEST(NerfactoModel, Bf16ForwardIsCloseToFp32) {
  NerfactoModel m32(tiny_config(Precision::fp32), 3, 1);
  NerfactoModel m16(tiny_config(Precision::bf16), 3, 1);  // same seed → same weights
  torch::NoGradGuard ng;
  // A field with non-trivial values: randomise the table like a trained one.
  auto g = at::make_generator<at::CPUGeneratorImpl>(4);
  m32->field->grid->table.copy_(torch::randn(m32->field->grid->table.sizes(), g) * 0.5);
  m16->field->grid->table.copy_(m32->field->grid->table);
  const auto u = torch::rand({4096, 3}, g);
  auto d = torch::rand({4096, 3}, g) - 0.5;
  d = d / d.norm(2, 1, true);
  const auto ids = torch::tensor({-1}, torch::kInt64);
  const FieldQuery a = m32->field->query(u, d, ids), b = m16->field->query(u, d, ids);
  const double rel_d = ((a.density - b.density).norm() / a.density.norm()).item<double>();
  const double rel_c = ((a.rgb - b.rgb).norm() / a.rgb.norm()).item<double>();
  std::printf("bf16 vs fp32 field forward: relative error density %.2e, rgb %.2e\n", rel_d, rel_c);
  EXPECT_LT(rel_d, 3e-2);
  EXPECT_LT(rel_c, 1e-2);
}

TEST(Mlp, FusedOpMatchesTheAutogradReference) {
  auto g = at::make_generator<at::CPUGeneratorImpl>(21);
  for (auto p : {Precision::fp32, Precision::bf16}) {
    Mlp mlp(13, 24, 5, 3, p, 7);
    auto x = torch::randn({300, 13}, g).requires_grad_(true);
    auto xr = x.detach().clone().requires_grad_(true);
    std::vector<torch::Tensor> wr;
    for (const auto& w : mlp->weights()) wr.push_back(w.detach().clone().requires_grad_(true));
    const auto coef = torch::randn({300, 5}, g);
    const auto y = mlp->forward(x), yr = mlp_reference(xr, wr, p);
    const double tol = p == Precision::fp32 ? 1e-5 : 2e-2;
    EXPECT_TRUE(torch::allclose(y, yr, tol, tol)) << to_string(p);
    (y * coef).sum().backward();
    (yr * coef).sum().backward();
    EXPECT_TRUE(torch::allclose(x.grad(), xr.grad(), tol, tol)) << to_string(p);
    for (size_t l = 0; l < wr.size(); ++l) {
      const auto& a = mlp->weights()[l].grad();
      const auto& b = wr[l].grad();
      EXPECT_LT(((a - b).norm() / b.norm()).item<double>(), p == Precision::fp32 ? 1e-5 : 2e-2)
          << to_string(p) << " layer " << l;
    }
  }
  // No input gradient requested: none computed, weight gradients still there.
  Mlp mlp(4, 8, 2, 2, Precision::fp32, 1);
  const auto y = mlp->forward(torch::randn({10, 4}));
  y.sum().backward();
  EXPECT_TRUE(mlp->weights()[0].grad().defined());
}
