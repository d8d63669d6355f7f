#include "neraf/acoustic/acoustic_model.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "neraf/acoustic/losses.h"

namespace neraf::acoustic {
namespace {

AcousticModelOptions small_options(GridMode mode) {
  auto o = acoustic_preset("cpu", 2, 33, 12);
  o.grid_mode = mode;
  o.nacf.trunk = {64, 64};
  o.nacf.bf16 = false;
  o.nacf.relative_geometry = false;  // the reference's input layout and position encoding
  o.nacf.position_max_freq_exp = 8.0;
  return o;
}

struct Batch {
  torch::Tensor t, mic, src, rot;
};

Batch random_batch(int64_t b, int64_t max_len) {
  return {torch::randint(max_len, {b}, torch::kInt64), torch::rand({b, 3}, torch::kFloat64),
          torch::rand({b, 3}, torch::kFloat64), torch::rand({b, 3}, torch::kFloat64)};
}

TEST(AcousticModel, PresetsResolveSizes) {
  const auto cpu = acoustic_preset("cpu", 2, 257, 78);
  EXPECT_EQ(cpu.grid.resolution, 32);
  EXPECT_EQ(cpu.grid.cells_per_update, 1024);
  EXPECT_EQ(cpu.nacf.in_features(), 256 + 163 + kRelativeGeometryDim);
  EXPECT_TRUE(cpu.nacf.bf16);
  EXPECT_TRUE(cpu.nacf.relative_geometry);
  const auto paper = acoustic_preset("paper", 1, 513, 60);
  EXPECT_EQ(paper.grid.resolution, 128);
  EXPECT_EQ(paper.grid.cells_per_update, 4096);
  EXPECT_EQ(paper.nacf.in_features(), 1187);
  EXPECT_EQ(paper.nacf.trunk, (std::vector<int64_t>{5096, 2048, 1024, 1024, 512}));
  EXPECT_FALSE(paper.nacf.bf16);
  EXPECT_FALSE(paper.nacf.relative_geometry);
  EXPECT_THROW(acoustic_preset("gpu", 1, 513, 60), std::exception);
  EXPECT_EQ(parse_grid_mode("zeros"), GridMode::kZeros);
  EXPECT_THROW(parse_grid_mode("off"), std::exception);
}

TEST(AcousticModel, SampledForwardShapeAndGradientToGrid) {
  torch::manual_seed(0);
  AcousticModel m(small_options(GridMode::kSampled));
  auto grid = torch::rand({7, 32, 32, 32}, torch::requires_grad());
  const auto b = random_batch(6, 12);
  const auto y = m->forward(grid, b.t, b.mic, b.src, b.rot);
  ASSERT_EQ(y.sizes(), (std::vector<int64_t>{6, 2, 33}));
  y.sum().backward();
  EXPECT_GT(grid.grad().abs().sum().item<float>(), 0.0f);
  // The scene feature is shared by the whole batch: same pose and frame → same output.
  const auto one =
      m->forward(grid, b.t.slice(0, 0, 1).repeat({2}), b.mic.slice(0, 0, 1).repeat({2, 1}),
                 b.src.slice(0, 0, 1).repeat({2, 1}), b.rot.slice(0, 0, 1).repeat({2, 1}));
  EXPECT_TRUE(torch::allclose(one[0], one[1]));
}

TEST(AcousticModel, ZerosModeIgnoresTheGridButKeepsResnet) {
  torch::manual_seed(1);
  AcousticModel m(small_options(GridMode::kZeros));
  ASSERT_TRUE(m->resnet3d());
  m->eval();
  const auto b = random_batch(4, 12);
  const auto a = m->forward(torch::rand({7, 32, 32, 32}), b.t, b.mic, b.src, b.rot);
  const auto c = m->forward(torch::Tensor(), b.t, b.mic, b.src, b.rot);
  EXPECT_TRUE(torch::equal(a, c));
  EXPECT_EQ(m->field()->options().in_features(), 256 + 163);
}

TEST(AcousticModel, NoneModeUsesNoGridLayout) {
  torch::manual_seed(2);
  AcousticModel m(small_options(GridMode::kNone));
  EXPECT_FALSE(m->resnet3d());
  EXPECT_EQ(m->field()->options().in_features(), 163);
  const auto b = random_batch(4, 12);
  const auto y = m->forward(torch::Tensor(), b.t, b.mic, b.src, b.rot);
  EXPECT_EQ(y.sizes(), (std::vector<int64_t>{4, 2, 33}));
  const auto h = nacf_input(torch::Tensor(), b.t, 12, b.mic, b.src, b.rot);
  EXPECT_TRUE(torch::allclose(y, m->field()->forward(h)));
}

TEST(AcousticModel, RelativeGeometryIsAppendedAfterTheReferenceInputs) {
  torch::manual_seed(4);
  auto o = small_options(GridMode::kNone);
  o.nacf.relative_geometry = true;
  o.nacf.box_min = {-1, 0, 1};
  o.nacf.box_max = {3, 2, 4};
  o.nacf.position_max_freq_exp = 1.0;
  AcousticModel m(o);
  EXPECT_EQ(m->field()->options().in_features(), 163 + kRelativeGeometryDim);
  // Positions in metres, some outside the box: the position encodings take the normalised
  // positions (zero outside), the relative geometry the metres.
  Batch b = random_batch(4, 12);
  b.mic = b.mic * 6 - 2;
  b.src = b.src * 6 - 2;
  const auto y = m->forward(torch::Tensor(), b.t, b.mic, b.src, b.rot);
  const auto mn = normalize_to_box(b.mic, o.nacf.box_min, o.nacf.box_max);
  const auto sn = normalize_to_box(b.src, o.nacf.box_min, o.nacf.box_max);
  EXPECT_GT(
      (sn.abs().sum(1) == 0).sum().item<int64_t>() + (mn.abs().sum(1) == 0).sum().item<int64_t>(),
      0);
  const auto h = torch::cat({nacf_input(torch::Tensor(), b.t, 12, mn, sn, b.rot, 1.0),
                             encode_relative_geometry(b.mic, b.src, b.rot, {4, 2, 3})},
                            1);
  EXPECT_TRUE(torch::allclose(y, m->field()->forward(h)));
}

TEST(AcousticModel, RenderStftMatchesPerFrameForwardInEvalMode) {
  torch::manual_seed(3);
  AcousticModel m(small_options(GridMode::kSampled));
  const auto grid = torch::rand({7, 32, 32, 32});
  m->forward(grid, torch::zeros({1}, torch::kInt64), torch::rand({1, 3}), torch::rand({1, 3}),
             torch::rand({1, 3}));  // a train-mode pass leaves no state behind
  const auto mic = torch::rand({3}, torch::kFloat64), src = torch::rand({3}, torch::kFloat64),
             rot = torch::tensor({0.5, 0.5, 1.0}, torch::kFloat64);
  ASSERT_TRUE(m->is_training());
  const auto stft = m->render_stft(grid, mic, src, rot);
  EXPECT_TRUE(m->is_training());  // mode restored
  EXPECT_TRUE(m->resnet3d()->is_training());
  ASSERT_EQ(stft.sizes(), (std::vector<int64_t>{2, 33, 12}));
  EXPECT_FALSE(stft.requires_grad());
  m->eval();
  torch::NoGradGuard g;
  for (int64_t t : {0, 5, 11}) {
    const auto y = m->forward(grid, torch::tensor({t}, torch::kInt64), mic.view({1, 3}),
                              src.view({1, 3}), rot.view({1, 3}));  // [1, C, F]
    EXPECT_TRUE(torch::allclose(stft.select(2, t), y[0], 1e-5, 1e-6)) << t;
  }
  const auto feature = m->scene_feature(grid);
  EXPECT_TRUE(torch::equal(m->render_stft_with_feature(feature, mic, src, rot), stft));
}

// End to end: toy radiance field → GridSampler → ResNet3D → NAcF → SC+SLMSE; the audio loss must
// reach the radiance field through the freshly written cells, and one Adam step must lower it.
TEST(AcousticModel, AudioLossReachesFieldThroughFreshCells) {
  torch::manual_seed(4);
  auto o = small_options(GridMode::kSampled);
  o.grid.resolution = 32;
  o.grid.cells_per_update = 4096;
  GridSampler sampler(o.grid);
  AcousticModel m(o);
  auto w = torch::full({3}, 0.5, torch::requires_grad());
  FieldQueryFn field = [&w](const torch::Tensor& u, const torch::Tensor& d) {
    auto density = 50.0 * torch::exp((u * w).sum(1));
    auto rgb = torch::sigmoid(u * w + 0.1 * d);
    return std::make_pair(density, rgb);
  };
  sampler->update(field);
  const auto b = random_batch(32, 12);
  const auto gt = torch::randn({32, 2, 33}) - 3.0;
  const auto pred = m->forward(sampler->grid(), b.t, b.mic, b.src, b.rot);
  spectral_loss(pred, gt).total.backward();
  ASSERT_TRUE(w.grad().defined());
  EXPECT_GT(w.grad().abs().sum().item<float>(), 0.0f);

  auto params = m->parameters();
  torch::optim::Adam opt(params, torch::optim::AdamOptions(1e-3).eps(1e-15));
  const double before = spectral_loss(pred, gt).total.item<double>();
  double after = before;
  for (int i = 0; i < 5; ++i) {
    opt.zero_grad();
    auto l = spectral_loss(m->forward(sampler->grid().detach(), b.t, b.mic, b.src, b.rot), gt);
    l.total.backward();
    opt.step();
    after = l.total.item<double>();
  }
  EXPECT_LT(after, before);
}

}  // namespace
}  // namespace neraf::acoustic
