#include "neraf/runtime/amx_gemm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "neraf/runtime/model_file.h"

namespace {

float bf16(float x) { return neraf::rt::bf16_to_float(neraf::rt::float_to_bf16(x)); }

void expect_product(int rows, int in, int out, int split) {
  std::mt19937 gen(uint32_t(rows * 131 + in * 7 + out));
  std::uniform_real_distribution<float> u(-1, 1);
  const size_t ld = size_t(in) + 3;  // a row stride wider than the row
  std::vector<float> x(size_t(rows) * ld), w(size_t(out) * in);
  for (float& v : x) v = u(gen);
  for (float& v : w) v = u(gen);
  const neraf::rt::AmxMatrix a(w.data(), out, in);
  const int m = neraf::rt::round_up(rows, 16);
  std::vector<uint16_t> tiles(size_t(m) * a.in_padded());
  neraf::rt::pack_activations(x.data(), rows, in, ld, m, a.in_padded(), tiles.data());
  std::vector<float> y(size_t(m) * a.out_padded(), -7.0f);
  const int mid = split ? neraf::rt::round_up(a.out_padded() / 2, 32) : a.out_padded();
  a.multiply(tiles.data(), m, y.data(), 0, mid);
  a.multiply(tiles.data(), m, y.data(), mid, a.out_padded());
  double worst = 0;
  for (int r = 0; r < m; ++r)
    for (int n = 0; n < a.out_padded(); ++n) {
      double want = 0;
      if (r < rows && n < out)
        for (int k = 0; k < in; ++k) want += double(bf16(x[r * ld + k])) * bf16(w[size_t(n) * in + k]);
      worst = std::max(worst, std::fabs(y[size_t(r) * a.out_padded() + n] - want));
    }
  EXPECT_LT(worst, 1e-5 * std::sqrt(double(in))) << rows << " x " << in << " -> " << out;
}

}  // namespace

TEST(AmxGemm, MatchesBfloat16ProductsWithPadding) {
  if (!neraf::rt::amx_bf16_available()) GTEST_SKIP() << "no AMX-BF16 on this machine";
  expect_product(16, 32, 32, 0);
  expect_product(78, 512, 96, 1);
  expect_product(21, 37, 45, 0);  // every dimension padded
  expect_product(48, 100, 130, 1);
}

TEST(AmxGemm, PackingRoundsToNearestEvenAndZeroPads) {
  const float x[2 * 3] = {1.0f, 1.0f + 0x1p-8f, -3.0f, 0.5f, 2.0f, 1.0f + 3 * 0x1p-8f};
  std::vector<uint16_t> t(16 * 32, 0xFFFF);
  neraf::rt::pack_activations(x, 2, 3, 3, 16, 32, t.data());
  EXPECT_EQ(neraf::rt::bf16_to_float(t[0]), 1.0f);
  EXPECT_EQ(neraf::rt::bf16_to_float(t[1]), 1.0f);  // a tie: to even
  EXPECT_EQ(neraf::rt::bf16_to_float(t[2]), -3.0f);
  EXPECT_EQ(neraf::rt::bf16_to_float(t[32 + 2]), 1.0f + 0x1p-6f);
  EXPECT_EQ(t[3], 0);        // padded columns
  EXPECT_EQ(t[2 * 32], 0);   // padded rows
  EXPECT_EQ(t[15 * 32 + 31], 0);
}
