#include "neraf/acoustic/acoustic_model.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "neraf/acoustic/losses.h"
#include "neraf/util/error.h"

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

TEST(AcousticModel, LocalGridFeaturesAreReadPerQueryFromTheStemMap) {
  torch::manual_seed(6);
  auto o = small_options(GridMode::kSampled);
  o.grid_features = GridFeatures::kLocal;
  o.segment_points = 4;
  o.nacf.world_to_field = {0.5, 0, 0, -0.25, 0, 0.5, 0, -0.25, 0, 0, 0.5, -0.25};
  AcousticModel m(o);
  const int64_t local = 4 * o.resnet.stem_channels;
  EXPECT_EQ(m->field()->options().in_features(), 163 + local);  // no pooled feature
  auto grid = torch::rand({7, 32, 32, 32}, torch::requires_grad());
  const Batch b = random_batch(5, 12);
  const SceneFeatures f = m->scene_features(grid);
  EXPECT_FALSE(f.global.defined());
  ASSERT_EQ(f.volume.sizes(), (std::vector<int64_t>{o.resnet.stem_channels, 16, 16, 16}));
  // The input: the no-grid layout, then the stem map read along each mic–source segment.
  const auto h = m->nacf_input(f, m->options().nacf, b.t, b.mic, b.src, b.rot);
  const auto want = torch::cat(
      {nacf_input(torch::Tensor(), b.t, 12, b.mic, b.src, b.rot),  // unit box: metres as they are
       local_geometry_features(
           f.volume,
           strided_map_coordinates(world_to_grid_input(b.mic, o.nacf.world_to_field), 32, 16),
           strided_map_coordinates(world_to_grid_input(b.src, o.nacf.world_to_field), 32, 16), 4)},
      1);
  EXPECT_TRUE(torch::allclose(h, want));
  // The gradient reaches the grid and the stem through the per-query features alone; the later
  // stages are not run.
  const auto y = m->forward(grid, b.t, b.mic, b.src, b.rot);
  y.sum().backward();
  EXPECT_GT(grid.grad().abs().sum().item<float>(), 0.0f);
  for (const auto& p : m->resnet3d()->named_parameters()) {
    const bool stem = p.key().rfind("conv1.", 0) == 0 || p.key().rfind("bn1.", 0) == 0;
    EXPECT_EQ(p.value().grad().defined(), stem) << p.key();
  }
  // Two poses of one frame now differ through the grid as well: moving the mic changes the
  // local part of the input.
  Batch moved = b;
  moved.mic = b.mic + 0.3;
  const auto h2 = m->nacf_input(f, m->options().nacf, moved.t, moved.mic, moved.src, moved.rot);
  EXPECT_FALSE(torch::allclose(h2.slice(1, 163), h.slice(1, 163)));
}

TEST(AcousticModel, BothGridFeaturesPutThePooledFeatureFirstAndTheLocalOnesLast) {
  torch::manual_seed(7);
  auto o = small_options(GridMode::kSampled);
  o.grid_features = GridFeatures::kBoth;
  AcousticModel m(o);
  const int64_t g = 256, local = 4 * o.resnet.stem_channels;
  EXPECT_EQ(m->field()->options().in_features(), g + 163 + local);
  m->eval();
  torch::NoGradGuard no_grad;
  const auto grid = torch::rand({7, 32, 32, 32});
  const SceneFeatures f = m->scene_features(grid);
  // The pooled feature is ResNet3D's output, as in the global design.
  torch::manual_seed(7);
  AcousticModel same_init(o);
  EXPECT_TRUE(torch::allclose(f.global, same_init->resnet3d()->forward(grid.unsqueeze(0))[0]));
  const Batch b = random_batch(3, 12);
  const auto h = m->nacf_input(f, m->options().nacf, b.t, b.mic, b.src, b.rot);
  EXPECT_TRUE(
      torch::allclose(h.slice(1, 0, g + 163), nacf_input(f.global, b.t, 12, b.mic, b.src, b.rot)));
  EXPECT_EQ(h.size(1), g + 163 + local);
  // Rendering from the features matches the per-frame forward.
  const auto stft = m->render_stft_with_feature(f, b.mic[0], b.src[0], b.rot[0]);  // [C, F, T]
  const auto y = m->forward(grid, torch::tensor({3}, torch::kInt64), b.mic.slice(0, 0, 1),
                            b.src.slice(0, 0, 1), b.rot.slice(0, 0, 1));
  EXPECT_TRUE(torch::allclose(stft.select(2, 3), y[0], 1e-5, 1e-6));
}

TEST(AcousticModel, PerQueryGridFeaturesNeedAGrid) {
  auto o = small_options(GridMode::kNone);
  o.grid_features = GridFeatures::kLocal;
  EXPECT_THROW(AcousticModel{o}, Error);
  EXPECT_EQ(parse_grid_features("both"), GridFeatures::kBoth);
  EXPECT_EQ(to_string(GridFeatures::kLocal), "local");
  EXPECT_THROW(parse_grid_features("pooled"), Error);
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
  const auto feature = m->scene_features(grid);
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
