#include "neraf/render/rir.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <random>
#include <vector>

#include "neraf/util/error.h"

namespace neraf::render {
namespace {

TEST(ParsePosition, AcceptsNumbers) {
  geometry::Vec3 p = parse_position("1,2,3", "--mic");
  EXPECT_DOUBLE_EQ(p.x, 1);
  EXPECT_DOUBLE_EQ(p.y, 2);
  EXPECT_DOUBLE_EQ(p.z, 3);
  p = parse_position(" 1.5, -2 ,3e-1", "--src");
  EXPECT_DOUBLE_EQ(p.x, 1.5);
  EXPECT_DOUBLE_EQ(p.y, -2);
  EXPECT_DOUBLE_EQ(p.z, 0.3);
}

TEST(ParsePosition, RejectsMalformedNamingTheFlag) {
  for (const char* bad :
       {"", "1,2", "1,2,3,4", "a,b,c", "1,,3", "nan,1,2", "1,2,inf", "1;2;3", "1,2,3x", "1 2 3"}) {
    try {
      parse_position(bad, "--src");
      ADD_FAILURE() << "accepted \"" << bad << "\"";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--src"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("X,Y,Z"), std::string::npos) << e.what();
    }
  }
}

TEST(InsideOpenBox, StrictBounds) {
  const data::Aabb box{{0, 0, 0}, {1, 2, 3}};
  EXPECT_TRUE(inside_open_box({0.5, 1, 1}, box));
  EXPECT_FALSE(inside_open_box({0, 1, 1}, box));  // on the face: zeroed by NeRAF (not in (0,1))
  EXPECT_FALSE(inside_open_box({0.5, 2.5, 1}, box));
  EXPECT_FALSE(inside_open_box({0.5, 1, -1}, box));
}

// A decaying noise burst, its log-magnitude STFT, and back through Griffin-Lim.
torch::Tensor test_log_stft(const dsp::StftParams& p, int channels, std::vector<float>* wave0) {
  std::mt19937 rng(3);
  std::normal_distribution<float> n(0, 1);
  std::vector<torch::Tensor> chans;
  for (int c = 0; c < channels; ++c) {
    std::vector<float> x(p.hop_length * 20);
    for (size_t i = 0; i < x.size(); ++i) x[i] = n(rng) * std::exp(-float(i) / 300.0f) * 0.1f;
    if (c == 0 && wave0) *wave0 = x;
    const dsp::Matrix m = dsp::log_magnitude(dsp::stft(x, p));
    chans.push_back(
        torch::from_blob(const_cast<float*>(m.data.data()), {m.rows, m.cols}, torch::kFloat32)
            .clone());
  }
  return torch::stack(chans);  // [C, F, T]
}

TEST(RirFromLogStft, ShapeRateDeterminismAndLevel) {
  const dsp::StftParams p = dsp::StftParams::soundspaces();
  std::vector<float> x;
  const torch::Tensor ls = test_log_stft(p, 2, &x);
  const int64_t T = ls.size(2);
  const io::AudioBuffer a = rir_from_log_stft(ls, p, 22050, {7});
  const io::AudioBuffer b = rir_from_log_stft(ls, p, 22050, {7});
  ASSERT_EQ(a.num_channels(), 2);
  EXPECT_EQ(a.sample_rate, 22050);
  EXPECT_EQ(a.num_frames(), p.hop_length * (T - 1));
  EXPECT_EQ(a.channels, b.channels);
  // Griffin-Lim keeps the magnitude: energies agree within a few percent... to a factor.
  double e_in = 0, e_out = 0;
  for (size_t i = 0; i < x.size(); ++i) e_in += double(x[i]) * x[i];
  for (float v : a.channels[0]) e_out += double(v) * v;
  EXPECT_GT(e_out, 0.5 * e_in);
  EXPECT_LT(e_out, 2.0 * e_in);
}

TEST(RenderRir, PassesThePoseToTheModel) {
  AudioModelInfo info;
  info.layout = data::AudioLayout::raf;
  info.sample_rate = 48000;
  info.stft = dsp::StftParams::raf();
  info.channels = 1;
  const torch::Tensor ls = test_log_stft(info.stft, 1, nullptr);
  int calls = 0;
  LogStftFn predict = [&](const torch::Tensor& mic, const torch::Tensor& src,
                          const torch::Tensor& yaw) {
    ++calls;
    EXPECT_EQ(mic.sizes(), (std::vector<int64_t>{1, 3}));
    EXPECT_DOUBLE_EQ(mic[0][2].item<double>(), 3.0);
    EXPECT_DOUBLE_EQ(src[0][0].item<double>(), 4.0);
    EXPECT_DOUBLE_EQ(yaw[0].item<double>(), 90.0);
    return ls.unsqueeze(0);
  };
  const io::AudioBuffer out = render_rir(predict, info, {1, 2, 3}, {4, 5, 6}, 90.0);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(out.num_channels(), 1);
  EXPECT_EQ(out.sample_rate, 48000);
  EXPECT_EQ(out.num_frames(), 256 * (ls.size(2) - 1));
}

}  // namespace
}  // namespace neraf::render
