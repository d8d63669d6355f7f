#include "neraf/acoustic/nacf.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <array>
#include <cmath>

#include "neraf/acoustic/positional_encoding.h"

namespace neraf::acoustic {
namespace {

using torch::indexing::Slice;

TEST(Nacf, PaperParameterCounts) {
  Nacf ss(nacf_paper_options(2, 257));
  EXPECT_EQ(ss->options().in_features(), 1187);
  EXPECT_EQ(ss->trunk_parameter_count(), 20165280);
  EXPECT_EQ(ss->head_parameter_count(), 263682);
  Nacf raf(nacf_paper_options(1, 513));
  EXPECT_EQ(raf->head_parameter_count(), 263169);
  // Layer widths as in the published code (5096, not 4096).
  const auto p = ss->named_parameters();
  EXPECT_EQ(p["soundfield.0.weight"].sizes(), (std::vector<int64_t>{5096, 1187}));
  EXPECT_EQ(p["soundfield.4.weight"].sizes(), (std::vector<int64_t>{512, 1024}));
  EXPECT_EQ(p["STFT_linear.1.weight"].sizes(), (std::vector<int64_t>{257, 512}));
}

TEST(Nacf, DefaultLinearInitBounds) {
  torch::manual_seed(0);
  Nacf net(nacf_cpu_options(1, 513, 256));
  const auto p = net->named_parameters();
  // PyTorch default: kaiming_uniform(a=√5) → U(±1/√fan_in) for weights, U(±1/√fan_in) for biases.
  const double bound = 1.0 / std::sqrt(static_cast<double>(256 + kPoseEncodingDim));
  EXPECT_LE(p["soundfield.0.weight"].abs().max().item<double>(), bound);
  EXPECT_GT(p["soundfield.0.weight"].abs().max().item<double>(), 0.99 * bound);
  EXPECT_LE(p["soundfield.0.bias"].abs().max().item<double>(), bound);
}

// rot as the datasets store a heading of `deg` degrees: ((cosθ+1)/2, 0.5, (sinθ+1)/2).
torch::Tensor stored_rot(double deg) {
  const double a = deg * M_PI / 180.0;
  return torch::tensor({{(std::cos(a) + 1) / 2, 0.5, (std::sin(a) + 1) / 2}}, torch::kFloat64);
}

TEST(Nacf, RelativeGeometryHandComputed) {
  // Audio box 4 × 2 × 4 m; source 1 m along +x from the mic, listener heading 90°.
  const auto mic = torch::tensor({{2.0, 1.0, 2.0}}, torch::kFloat64);
  const auto src = torch::tensor({{3.0, 1.0, 2.0}}, torch::kFloat64);
  const auto g = encode_relative_geometry(mic, src, stored_rot(90), {4, 2, 4});
  ASSERT_EQ(g.sizes(), (std::vector<int64_t>{1, kRelativeGeometryDim}));
  EXPECT_EQ(g.dtype(), torch::kFloat32);
  // φ = 0, θ = 90°: φ − θ = −90°, φ + θ = 90°, for k = 1, 2, 3 (cos, sin of each).
  const double expected_angles[] = {0, -1, 0, 1, -1, 0, -1, 0, 0, 1, 0, -1};
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(g[0][i].item<double>(), expected_angles[i], 1e-6) << i;
  EXPECT_NEAR(g[0][12].item<double>(), 0.0, 1e-6);  // level with the listener
  EXPECT_NEAR(g[0][13].item<double>(), 1.0, 1e-6);
  const double rel = 1.0 / 6.0;  // |d| = 1 m, box diagonal √(16 + 4 + 16) = 6 m
  EXPECT_NEAR(g[0][14].item<double>(), rel, 1e-6);
  EXPECT_NEAR(g[0][15].item<double>(), 0.0, 1e-6);  // ln 1
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(g[0][16 + 2 * k].item<double>(), std::sin(2 * M_PI * (1 << k) * rel), 1e-6);
    EXPECT_NEAR(g[0][17 + 2 * k].item<double>(), std::cos(2 * M_PI * (1 << k) * rel), 1e-6);
  }
  // Straight above: elevation 1; the distance is clamped to 5 cm when the two coincide.
  const auto up = encode_relative_geometry(mic, torch::tensor({{2.0, 2.0, 2.0}}, torch::kFloat64),
                                           stored_rot(0), {4, 2, 4});
  EXPECT_NEAR(up[0][12].item<double>(), 1.0, 1e-6);
  const auto same = encode_relative_geometry(mic, mic, stored_rot(0), {4, 2, 4});
  EXPECT_NEAR(same[0][15].item<double>(), std::log(0.05), 1e-6);
}

TEST(Nacf, RelativeGeometryFollowsTheListenerNotTheRoom) {
  // Turning the source direction and the heading by the same angle about y leaves the
  // heading-relative features (φ − θ) and the distance features unchanged.
  const std::array<double, 3> extent{4, 2, 4};
  const auto mic = torch::tensor({{2.0, 0.8, 2.0}}, torch::kFloat64);
  auto source_at = [&](double deg) {
    const double a = deg * M_PI / 180.0;  // 1.2 m away at azimuth 30° + deg, 0.2 m higher
    return torch::tensor(
        {{2.0 + 1.2 * std::cos(a + M_PI / 6), 1.0, 2.0 + 1.2 * std::sin(a + M_PI / 6)}},
        torch::kFloat64);
  };
  const auto a = encode_relative_geometry(mic, source_at(0), stored_rot(10), extent);
  for (double turn : {90.0, 180.0, -35.0}) {
    const auto b = encode_relative_geometry(mic, source_at(turn), stored_rot(10 + turn), extent);
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 2; ++j)  // cos and sin of k(φ − θ)
        EXPECT_NEAR(a[0][4 * k + j].item<double>(), b[0][4 * k + j].item<double>(), 1e-5);
    EXPECT_TRUE(torch::allclose(a.slice(1, 12), b.slice(1, 12), 1e-5, 1e-6));
  }
}

// A source outside the audio box (RAF loudspeakers often are: the box is the train mics ± 1 m):
// its position encoding is the reference's zero vector, but the relative geometry is computed from
// the metres, so its direction and distance are right.
TEST(Nacf, SourceOutsideTheBoxKeepsItsDirectionAndDistance) {
  NacfOptions o = nacf_cpu_options(1, 9, 0);
  o.relative_geometry = true;
  o.box_min = {-1.0, 0.0, -2.0};
  o.box_max = {3.0, 2.5, 1.5};  // extent 4 × 2.5 × 3.5 m
  const auto t = torch::tensor({0}, torch::kInt64);
  const auto mic = torch::tensor({{1.0, 1.0, 0.0}}, torch::kFloat64);  // inside
  const auto src = torch::tensor({{1.0, 1.0, 5.0}}, torch::kFloat64);  // 5 m along +z: outside
  const auto h = nacf_input(o, torch::Tensor(), t, 12, mic, src, stored_rot(0));
  ASSERT_EQ(h.sizes(), (std::vector<int64_t>{1, 163 + kRelativeGeometryDim}));
  // No-grid order [mic 63, src 63, time 21, rot 16, relative 22]: the source encodes as zeros.
  const auto zeros = torch::zeros({1, 3}, torch::kFloat64);
  EXPECT_TRUE(torch::equal(h.slice(1, 63, 126), encode_position(zeros, o.position_max_freq_exp)));
  EXPECT_TRUE(torch::equal(
      h.slice(1, 0, 63),
      encode_position(normalize_to_box(mic, o.box_min, o.box_max), o.position_max_freq_exp)));
  const auto g = h.slice(1, 163);
  // Heading 0, source at azimuth atan2(dz, dx) = 90°: cos, sin of k·90° for both senses.
  const double expected_angles[] = {0, 1, 0, 1, -1, 0, -1, 0, 0, -1, 0, -1};
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(g[0][i].item<double>(), expected_angles[i], 1e-6) << i;
  EXPECT_NEAR(g[0][12].item<double>(), 0.0, 1e-6);                    // level
  EXPECT_NEAR(g[0][14].item<double>(), 5.0 / std::sqrt(34.5), 1e-6);  // 5 m / box diagonal
  EXPECT_NEAR(g[0][15].item<double>(), std::log(5.0), 1e-6);          // ln 5 m
  // From the normalised positions the source would sit at the zero vector, i.e. at the box's
  // minimum corner, 3 m from the mic in another direction.
  EXPECT_GT(std::abs(g[0][15].item<double>() - std::log(3.0)), 0.4);
}

TEST(Nacf, ShapesAndTanhRange) {
  torch::manual_seed(1);
  Nacf net(nacf_cpu_options(2, 257, 256));
  EXPECT_EQ(net->options().in_features(), 256 + 163);
  const auto h = torch::randn({5, 419});
  const auto y = net->forward(h);
  ASSERT_EQ(y.sizes(), (std::vector<int64_t>{5, 2, 257}));
  // Push the heads into saturation: outputs stay strictly inside (−10, 10) and reach ±10 closely.
  {
    torch::NoGradGuard g;
    for (auto& kv : net->named_parameters()) {
      if (kv.key().rfind("STFT_linear.0.bias", 0) == 0) kv.value().fill_(50.0);
      if (kv.key().rfind("STFT_linear.1.bias", 0) == 0) kv.value().fill_(-50.0);
    }
  }
  const auto s = net->forward(h);
  EXPECT_LE(s.abs().max().item<float>(), 10.0f);
  EXPECT_NEAR(s.select(1, 0).min().item<float>(), 10.0f, 1e-3);
  EXPECT_NEAR(s.select(1, 1).max().item<float>(), -10.0f, 1e-3);
  // Channel c comes from head c only.
  const auto y0 = net->forward(h);
  EXPECT_GT(y0.select(1, 0).min().item<float>(), 0.0f);
  EXPECT_LT(y0.select(1, 1).max().item<float>(), 0.0f);
}

TEST(Nacf, EncodersHandValues) {
  // Rot θ = 90°: stored (0.5, 0.5, 1) → tcnn maps 2v − 1 → (0, 0, 1).
  const auto r90 = encode_rot(torch::tensor({0.5, 0.5, 1.0}, torch::kFloat64).view({1, 3}));
  ASSERT_EQ(r90.sizes(), (std::vector<int64_t>{1, 16}));
  std::vector<double> want(16, 0.0);
  want[0] = 0.28209479;
  want[2] = 0.48860251;
  want[6] = 0.94617470 - 0.31539157;
  want[12] = 0.37317633 * 2.0;
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(r90[0][i].item<float>(), want[i], 1e-6) << i;
  // θ = 0°: stored (1, 0.5, 0.5) → (1, 0, 0).
  const auto r0 = encode_rot(torch::tensor({1.0, 0.5, 0.5}, torch::kFloat64).view({1, 3}));
  std::fill(want.begin(), want.end(), 0.0);
  want[0] = 0.28209479;
  want[3] = -0.48860251;
  want[6] = -0.31539157;
  want[8] = 0.54627422;
  want[13] = 0.45704580;
  want[15] = -0.59004359;
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(r0[0][i].item<float>(), want[i], 1e-6) << i;

  // Out-of-box positions arrive as zero vectors: sin 0, cos 1, raw 0.
  const auto p0 = encode_position(torch::zeros({1, 3}, torch::kFloat64));
  ASSERT_EQ(p0.sizes(), (std::vector<int64_t>{1, 63}));
  EXPECT_EQ(p0.scalar_type(), torch::kFloat32);
  EXPECT_NEAR(p0.slice(1, 0, 30).abs().max().item<float>(), 0.0f, 1e-7);
  EXPECT_NEAR(p0.slice(1, 30, 60).min().item<float>(), 1.0f, 1e-7);
  // Time: t/(max_len − 1); frame 39 of 79 → 0.5 → sin(π·f).
  const auto te = encode_time(torch::tensor({39}, torch::kInt64), 79);
  ASSERT_EQ(te.sizes(), (std::vector<int64_t>{1, 21}));
  EXPECT_NEAR(te[0][0].item<float>(), 0.0f, 1e-6);    // sin(π)
  EXPECT_NEAR(te[0][10].item<float>(), -1.0f, 1e-6);  // cos(π)
  EXPECT_FLOAT_EQ(te[0][20].item<float>(), 0.5f);
}

TEST(Nacf, InputOrderWithAndWithoutGrid) {
  const int64_t b = 3, g = 8, max_len = 60;
  const auto feature = torch::arange(g, torch::kFloat32) + 100.0;
  const auto t = torch::tensor({0, 17, 59}, torch::kInt64);
  const auto mic = torch::rand({b, 3}, torch::kFloat64);
  const auto src = torch::rand({b, 3}, torch::kFloat64);
  const auto rot = torch::rand({b, 3}, torch::kFloat64);
  const auto h = nacf_input(feature, t, max_len, mic, src, rot);
  ASSERT_EQ(h.sizes(), (std::vector<int64_t>{b, g + 163}));
  EXPECT_EQ(h.scalar_type(), torch::kFloat32);
  const auto te = encode_time(t, max_len), me = encode_position(mic), se = encode_position(src),
             re = encode_rot(rot);
  EXPECT_TRUE(torch::equal(h.slice(1, 0, g), feature.expand({b, g})));
  EXPECT_TRUE(torch::equal(h.slice(1, g, g + 21), te));
  EXPECT_TRUE(torch::equal(h.slice(1, g + 21, g + 84), me));
  EXPECT_TRUE(torch::equal(h.slice(1, g + 84, g + 147), se));
  EXPECT_TRUE(torch::equal(h.slice(1, g + 147, g + 163), re));
  // Raw inputs sit at the end of each NeRF encoding block.
  EXPECT_FLOAT_EQ(h[1][g + 20].item<float>(), 17.0f / 59.0f);
  EXPECT_FLOAT_EQ(h[2][g + 21 + 60].item<float>(), static_cast<float>(mic[2][0].item<double>()));

  // No grid: [mic, source, time, rot].
  const auto n = nacf_input(torch::Tensor(), t, max_len, mic, src, rot);
  ASSERT_EQ(n.sizes(), (std::vector<int64_t>{b, 163}));
  EXPECT_TRUE(torch::equal(n.slice(1, 0, 63), me));
  EXPECT_TRUE(torch::equal(n.slice(1, 63, 126), se));
  EXPECT_TRUE(torch::equal(n.slice(1, 126, 147), te));
  EXPECT_TRUE(torch::equal(n.slice(1, 147, 163), re));

  // A per-sample grid feature [B, G] is accepted as is.
  const auto per = torch::rand({b, g});
  EXPECT_TRUE(torch::equal(nacf_input(per, t, max_len, mic, src, rot).slice(1, 0, g), per));
  EXPECT_THROW(nacf_input(torch::rand({2, g}), t, max_len, mic, src, rot), std::exception);
}

TEST(Nacf, Bf16TrunkTracksFp32) {
  torch::manual_seed(4);
  NacfOptions o = nacf_cpu_options(2, 257, 256);
  Nacf net(o);
  const auto h = torch::randn({256, o.in_features()});
  const auto ref = net->forward(h);
  o.bf16 = true;
  Nacf low(o);
  {
    torch::NoGradGuard g;
    auto dst = low->parameters();
    auto src = net->parameters();
    for (size_t i = 0; i < dst.size(); ++i) dst[i].copy_(src[i]);
  }
  const auto out = low->forward(h);
  EXPECT_EQ(out.scalar_type(), torch::kFloat32);
  const double scale = ref.abs().mean().item<double>();
  const double err = (out - ref).abs().mean().item<double>();
  // bf16 keeps 8 mantissa bits (2^-9 ≈ 2e-3 relative rounding per operand).
  EXPECT_LT(err / scale, 1.5e-2) << "mean |bf16 − fp32| = " << err << ", mean |fp32| = " << scale;
  // Gradients land on the fp32 master weights.
  out.pow(2).mean().backward();
  for (const auto& p : low->parameters()) {
    ASSERT_TRUE(p.grad().defined());
    EXPECT_EQ(p.grad().scalar_type(), torch::kFloat32);
  }
}

// The decay heads' output against the formula computed by hand from the weights, its gradients
// against the chain rule, and τ read from the right column in both input layouts.
TEST(Nacf, DecayHeadsAddTimeTimesSlope) {
  const int64_t b = 4, max_len = 30;
  const auto t = torch::tensor({0, 7, 22, 29}, torch::kInt64);
  const auto mic = torch::rand({b, 3}, torch::kFloat64);
  const auto src = torch::rand({b, 3}, torch::kFloat64);
  const auto rot = torch::rand({b, 3}, torch::kFloat64);
  const auto tau = t.to(torch::kFloat32) / double(max_len - 1);  // [B]
  for (const int64_t g : {int64_t{16}, int64_t{0}}) {
    torch::manual_seed(9);
    NacfOptions o = nacf_cpu_options(2, 5, g);
    o.trunk = {12, 12};
    o.decay_heads = true;
    Nacf net(o);
    const auto params = net->named_parameters();
    const auto w = [&](const std::string& name) { return params[name]; };
    const auto h = nacf_input(g > 0 ? torch::rand({g}) : torch::Tensor(), t, max_len, mic, src,
                              rot);  // [B, in]
    EXPECT_TRUE(torch::equal(h.select(1, o.time_input_column()), tau)) << "G = " << g;
    // The trunk by hand, then each channel's level and slope.
    auto x = h;
    for (const std::string i : {"0", "1"}) {
      const std::string l = "soundfield." + i;
      x = torch::leaky_relu(torch::matmul(x, w(l + ".weight").t()) + w(l + ".bias"), 0.1);
    }
    std::vector<torch::Tensor> z;
    for (const std::string c : {"0", "1"}) {
      const std::string level = "STFT_linear." + c, slope = "decay_slope." + c;
      z.push_back(torch::matmul(x, w(level + ".weight").t()) + w(level + ".bias") +
                  tau.unsqueeze(1) *
                      (torch::matmul(x, w(slope + ".weight").t()) + w(slope + ".bias")));
    }
    const auto pre = torch::stack(z, 1).detach();  // [B, C, F]
    const auto y = net->forward(h);
    EXPECT_TRUE(torch::allclose(y, 10.0 * torch::tanh(pre), 1e-5, 1e-5)) << "G = " << g;
    // d Σy / d slope bias[f] of channel 0 = Σ_b 10·(1 − tanh²(z))·τ_b.
    y.sum().backward();
    const auto expected =
        (10.0 * (1 - torch::tanh(pre.select(1, 0)).pow(2)) * tau.unsqueeze(1)).sum(0);  // [F]
    EXPECT_TRUE(torch::allclose(w("decay_slope.0.bias").grad(), expected, 1e-4, 1e-5))
        << "G = " << g;
    // At τ = 0 the slope heads get no gradient from that row: the first query alone.
    net->zero_grad();
    net->forward(h.slice(0, 0, 1)).sum().backward();
    EXPECT_EQ(w("decay_slope.0.bias").grad().abs().max().item<float>(), 0.0f);
  }
  // Off (every preset): no slope heads, the reference's parameters only.
  Nacf plain(nacf_cpu_options(2, 5, 16));
  EXPECT_FALSE(plain->named_parameters().contains("decay_slope.0.bias"));
  NacfOptions on = nacf_cpu_options(2, 5, 16);
  on.decay_heads = true;
  EXPECT_EQ(Nacf(on)->head_parameter_count(), 2 * plain->head_parameter_count());
}

}  // namespace
}  // namespace neraf::acoustic
