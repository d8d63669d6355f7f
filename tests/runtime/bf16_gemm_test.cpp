#include "neraf/runtime/bf16_gemm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "neraf/runtime/model_file.h"

namespace {

float bf16(float x) { return neraf::rt::bf16_to_float(neraf::rt::float_to_bf16(x)); }

using neraf::rt::Bf16Kernel;

void expect_product(Bf16Kernel kernel, int rows, int in, int out, int split) {
  std::mt19937 gen(uint32_t(rows * 131 + in * 7 + out));
  std::uniform_real_distribution<float> u(-1, 1);
  const size_t ld = size_t(in) + 3;  // a row stride wider than the row
  std::vector<float> x(size_t(rows) * ld), w(size_t(out) * in);
  for (float& v : x) v = u(gen);
  for (float& v : w) v = u(gen);
  const neraf::rt::Bf16Matrix a(w.data(), out, in, kernel);
  const int m = neraf::rt::round_up(rows, 16);
  std::vector<uint16_t> tiles(size_t(m) * a.in_padded());
  neraf::rt::pack_activations(x.data(), rows, in, ld, m, a.in_padded(), tiles.data());
  std::vector<float> y(size_t(m) * a.out_padded(), -7.0f);
  const int mid = split ? neraf::rt::round_up(a.out_padded() / 2, 32) : a.out_padded();
  a.multiply(tiles.data(), m, y.data(), 0, mid);
  a.multiply(tiles.data(), m, y.data(), mid, a.out_padded());
  if (split) {  // the columns computed in two parts are those of one product, bit for bit
    std::vector<float> whole(y.size(), -7.0f);
    a.multiply(tiles.data(), m, whole.data(), 0, a.out_padded());
    EXPECT_EQ(whole, y) << bf16_kernel_name(kernel);
  }
  double worst = 0;
  for (int r = 0; r < m; ++r)
    for (int n = 0; n < a.out_padded(); ++n) {
      double want = 0;
      if (r < rows && n < out)
        for (int k = 0; k < in; ++k)
          want += double(bf16(x[r * ld + k])) * bf16(w[size_t(n) * in + k]);
      worst = std::max(worst, std::fabs(y[size_t(r) * a.out_padded() + n] - want));
    }
  EXPECT_LT(worst, 1e-5 * std::sqrt(double(in)))
      << bf16_kernel_name(kernel) << ": " << rows << " x " << in << " -> " << out;
}

void expect_products(Bf16Kernel kernel) {
  if (!neraf::rt::bf16_kernel_available(kernel))
    GTEST_SKIP() << "no " << bf16_kernel_name(kernel) << " bf16 kernel on this machine";
  expect_product(kernel, 16, 32, 32, 0);
  expect_product(kernel, 78, 512, 96, 1);
  expect_product(kernel, 21, 37, 45, 0);  // every dimension padded
  expect_product(kernel, 48, 100, 130, 1);
}

}  // namespace

TEST(Bf16Gemm, AmxMatchesBfloat16ProductsWithPadding) { expect_products(Bf16Kernel::amx); }

TEST(Bf16Gemm, Avx512MatchesBfloat16ProductsWithPadding) { expect_products(Bf16Kernel::avx512); }

TEST(Bf16Gemm, TheBestKernelIsAvailable) {
  const Bf16Kernel best = neraf::rt::best_bf16_kernel();
  EXPECT_EQ(neraf::rt::bf16_kernel_available(best), best != Bf16Kernel::none);
  if (neraf::rt::bf16_kernel_available(Bf16Kernel::amx)) {
    EXPECT_EQ(best, Bf16Kernel::amx);
  }
  if (best == Bf16Kernel::none) {
    EXPECT_FALSE(neraf::rt::bf16_kernel_available(Bf16Kernel::avx512));
  }
}

TEST(Bf16Gemm, AMatrixForAKernelThatCannotRunIsRefused) {
  const float w[1] = {1.0f};
  EXPECT_THROW(neraf::rt::Bf16Matrix(w, 1, 1, Bf16Kernel::none), std::invalid_argument);
  for (Bf16Kernel k : {Bf16Kernel::avx512, Bf16Kernel::amx})
    if (!neraf::rt::bf16_kernel_available(k)) {
      EXPECT_THROW(neraf::rt::Bf16Matrix(w, 1, 1, k), std::invalid_argument);
    }
}

TEST(Bf16Gemm, PackingRoundsToNearestEvenAndZeroPads) {
  const float x[2 * 3] = {1.0f, 1.0f + 0x1p-8f, -3.0f, 0.5f, 2.0f, 1.0f + 3 * 0x1p-8f};
  std::vector<uint16_t> t(16 * 32, 0xFFFF);
  neraf::rt::pack_activations(x, 2, 3, 3, 16, 32, t.data());
  EXPECT_EQ(neraf::rt::bf16_to_float(t[0]), 1.0f);
  EXPECT_EQ(neraf::rt::bf16_to_float(t[1]), 1.0f);  // a tie: to even
  EXPECT_EQ(neraf::rt::bf16_to_float(t[2]), -3.0f);
  EXPECT_EQ(neraf::rt::bf16_to_float(t[32 + 2]), 1.0f + 0x1p-6f);
  EXPECT_EQ(t[3], 0);       // padded columns
  EXPECT_EQ(t[2 * 32], 0);  // padded rows
  EXPECT_EQ(t[15 * 32 + 31], 0);
}
