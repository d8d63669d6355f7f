#include "neraf/acoustic/positional_encoding.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

namespace neraf::acoustic {
namespace {

TEST(NerfEncoding, Dims) {
  NerfEncodingOptions o;
  o.in_dim = 1;
  EXPECT_EQ(nerf_encoding_dim(o), 21);
  o.in_dim = 3;
  EXPECT_EQ(nerf_encoding_dim(o), 63);
  o.include_input = false;
  EXPECT_EQ(nerf_encoding_dim(o), 60);
}

TEST(NerfEncoding, FrequenciesAreNonIntegerPowersOfTwo) {
  const auto f = nerf_encoding_frequencies(NerfEncodingOptions{});
  ASSERT_EQ(f.size(0), 10);
  // 2^(8k/9), as listed in neraf-reference.md §1.2.
  const double listed[10] = {1.0,    1.852,  3.429,  6.350,   11.758,
                             21.773, 40.317, 74.658, 138.248, 256.0};
  for (int k = 0; k < 10; ++k) {
    const double v = f[k].item<double>();
    EXPECT_NEAR(v, std::pow(2.0, 8.0 * k / 9.0), 2e-6 * v) << k;
    EXPECT_NEAR(v, listed[k], 1e-3) << k;
    // Computed in float32 like the reference: exactly representable as float.
    EXPECT_EQ(v, static_cast<double>(static_cast<float>(v))) << k;
  }
}

TEST(NerfEncoding, HandValues3d) {
  const double x[3] = {0.1, 0.5, 0.8};
  auto in = torch::tensor({x[0], x[1], x[2]}, torch::kFloat64).view({1, 3});
  const auto out = nerf_encode(in, NerfEncodingOptions{});
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{1, 63}));
  EXPECT_EQ(out.scalar_type(), torch::kFloat64);
  const auto f = nerf_encoding_frequencies(NerfEncodingOptions{});
  for (int d = 0; d < 3; ++d) {
    for (int k = 0; k < 10; ++k) {
      const double s = 2.0 * M_PI * x[d] * f[k].item<double>();
      EXPECT_NEAR(out[0][d * 10 + k].item<double>(), std::sin(s), 1e-11) << d << "," << k;
      EXPECT_NEAR(out[0][30 + d * 10 + k].item<double>(), std::cos(s), 1e-11) << d << "," << k;
    }
    EXPECT_EQ(out[0][60 + d].item<double>(), x[d]);  // raw input appended last
  }
  // A few literal anchors: x = 0.5, f = 1 → sin(π) = 0, cos(π) = −1; x = 0.1, f = 1 → sin(0.2π).
  EXPECT_NEAR(out[0][10].item<double>(), 0.0, 1e-12);
  EXPECT_NEAR(out[0][40].item<double>(), -1.0, 1e-12);
  EXPECT_NEAR(out[0][0].item<double>(), 0.5877852522924731, 1e-12);
}

TEST(NerfEncoding, TimeAnchorsAndBatchShape) {
  NerfEncodingOptions o;
  o.in_dim = 1;
  const auto in = torch::tensor({0.0, 0.25}, torch::kFloat32).view({2, 1});
  const auto out = nerf_encode(in, o);
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{2, 21}));
  EXPECT_EQ(out.scalar_type(), torch::kFloat32);
  for (int k = 0; k < 10; ++k) {
    EXPECT_NEAR(out[0][k].item<float>(), 0.0f, 1e-6);       // sin(0)
    EXPECT_NEAR(out[0][10 + k].item<float>(), 1.0f, 1e-6);  // cos(0)
  }
  EXPECT_NEAR(out[1][0].item<float>(), 1.0f, 1e-6);   // sin(2π·0.25·1) = 1
  EXPECT_NEAR(out[1][10].item<float>(), 0.0f, 1e-6);  // cos(π/2) = 0
  EXPECT_NEAR(out[1][9].item<float>(), 0.0f, 1e-4);   // sin(2π·0.25·256) = sin(128π) = 0
  EXPECT_NEAR(out[1][19].item<float>(), 1.0f, 1e-4);
  EXPECT_EQ(out[1][20].item<float>(), 0.25f);
}

TEST(NerfEncoding, LeadingDimsPreserved) {
  const auto in = torch::rand({4, 5, 3}, torch::kFloat64);
  const auto out = nerf_encode(in, NerfEncodingOptions{});
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{4, 5, 63}));
  const auto flat = nerf_encode(in.view({20, 3}), NerfEncodingOptions{});
  EXPECT_TRUE(torch::equal(out.view({20, 63}), flat));
}

}  // namespace
}  // namespace neraf::acoustic
