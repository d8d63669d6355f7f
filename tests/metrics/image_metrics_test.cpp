// PSNR / SSIM against hand-computed values and a literal (slow) transcription of torchmetrics'
// algorithm: reflect-pad, 2-D Gaussian correlation over the padded image, crop, mean.
#include "neraf/metrics/image_metrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "neraf/util/error.h"

namespace neraf::metrics {
namespace {

ImageRGB random_image(int h, int w, int c, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  ImageRGB im(h, w, c);
  for (float& v : im.pixels) v = u(rng);
  return im;
}

// torchmetrics, step by step, without separability or the crop shortcut.
double slow_ssim(const ImageRGB& x, const ImageRGB& y, double data_range, bool crop = true) {
  const int k = 11, p = 5;
  const double sigma = 1.5;
  std::vector<double> g(k);
  double gs = 0.0;
  for (int i = 0; i < k; ++i) {
    g[i] = std::exp(-std::pow((i - 5) / sigma, 2) / 2);
    gs += g[i];
  }
  std::vector<std::vector<double>> kernel(k, std::vector<double>(k));
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b) kernel[a][b] = (g[a] / gs) * (g[b] / gs);
  const int H = x.height, W = x.width;
  auto reflect = [](int i, int n) { return i < 0 ? -i : (i >= n ? 2 * (n - 1) - i : i); };
  const double c1 = std::pow(0.01 * data_range, 2), c2 = std::pow(0.03 * data_range, 2);
  double total = 0.0;
  long count = 0;
  for (int c = 0; c < x.channels; ++c) {
    // Padded images [H + 2p][W + 2p].
    std::vector<std::vector<double>> px(H + 2 * p, std::vector<double>(W + 2 * p));
    auto py = px;
    for (int i = 0; i < H + 2 * p; ++i)
      for (int j = 0; j < W + 2 * p; ++j) {
        px[i][j] = x.at(reflect(i - p, H), reflect(j - p, W), c);
        py[i][j] = y.at(reflect(i - p, H), reflect(j - p, W), c);
      }
    for (int i = 0; i < H; ++i)
      for (int j = 0; j < W; ++j) {
        double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
        for (int a = 0; a < k; ++a)
          for (int b = 0; b < k; ++b) {
            const double w = kernel[a][b], u = px[i + a][j + b], v = py[i + a][j + b];
            mx += w * u;
            my += w * v;
            sxx += w * u * u;
            syy += w * v * v;
            sxy += w * u * v;
          }
        const double vx = std::max(0.0, sxx - mx * mx), vy = std::max(0.0, syy - my * my);
        const double s = ((2 * mx * my + c1) * (2 * (sxy - mx * my) + c2)) /
                         ((mx * mx + my * my + c1) * (vx + vy + c2));
        if (!crop || (i >= p && i < H - p && j >= p && j < W - p)) {  // the crop
          total += s;
          ++count;
        }
      }
  }
  return total / double(count);
}

TEST(Psnr, IdenticalImagesAreInfinite) {
  const ImageRGB a = random_image(8, 9, 3, 1);
  EXPECT_EQ(psnr(a.view(), a.view()), std::numeric_limits<double>::infinity());
}

TEST(Psnr, ConstantOffsetGivesTheClosedForm) {
  ImageRGB a = random_image(10, 7, 3, 2), b = a;
  for (float& v : a.pixels) v *= 0.8f;  // keep a + 0.1 inside [0, 1]
  b = a;
  for (float& v : b.pixels) v += 0.1f;
  // MSE = 0.01 -> 10 log10(1 / 0.01) = 20 dB (float rounding of the offset only).
  EXPECT_NEAR(psnr(b.view(), a.view()), 20.0, 1e-5);
  EXPECT_NEAR(psnr(b.view(), a.view(), 2.0), 20.0 + 20.0 * std::log10(2.0), 1e-5);
  // Half the pixels off by 0.2, the rest exact: MSE = 0.02 over all values.
  ImageRGB c(4, 4, 3, 0.5f), d(4, 4, 3, 0.5f);
  for (size_t i = 0; i < d.pixels.size(); i += 2) d.pixels[i] = 0.7f;
  EXPECT_NEAR(psnr(d.view(), c.view()), 10.0 * std::log10(1.0 / 0.02), 1e-5);
}

TEST(Psnr, ShapeMismatchIsAUserError) {
  const ImageRGB a(4, 4, 3), b(4, 5, 3);
  EXPECT_THROW(psnr(a.view(), b.view()), Error);
}

TEST(Ssim, GaussianWindowIsTorchmetrics) {
  const std::vector<double> w = ssim_gaussian_window(1.5);
  ASSERT_EQ(w.size(), 11u);
  double sum = 0.0, z = 0.0;
  for (int i = -5; i <= 5; ++i) z += std::exp(-(i / 1.5) * (i / 1.5) / 2);
  for (int i = 0; i < 11; ++i) {
    sum += w[i];
    EXPECT_DOUBLE_EQ(w[i], w[10 - i]);
    EXPECT_NEAR(w[i], std::exp(-((i - 5) / 1.5) * ((i - 5) / 1.5) / 2) / z, 1e-15);
  }
  EXPECT_NEAR(sum, 1.0, 1e-15);
  EXPECT_EQ(ssim_gaussian_window(0.5).size(), 5u);  // int(3.5·0.5 + 0.5)·2 + 1
}

TEST(Ssim, IdenticalImagesGiveOne) {
  const ImageRGB a = random_image(20, 17, 3, 3);
  EXPECT_NEAR(ssim(a.view(), a.view()), 1.0, 1e-12);
}

TEST(Ssim, ConstantImagesGiveTheLuminanceTerm) {
  // Zero variances and covariance: SSIM = (2ab + c1)/(a² + b² + c1), c1 = (0.01·range)².
  const ImageRGB a(12, 12, 3, 0.2f), b(12, 12, 3, 0.6f);
  SsimOptions o;
  o.data_range = 1.0;
  const double fa = 0.2f, fb = 0.6f, c1 = 1e-4;
  EXPECT_NEAR(ssim(a.view(), b.view(), o), (2 * fa * fb + c1) / (fa * fa + fb * fb + c1), 1e-12);
}

TEST(Ssim, MatchesTheLiteralTorchmetricsAlgorithm) {
  const ImageRGB x = random_image(16, 13, 3, 4);
  ImageRGB y = x;
  std::mt19937 rng(5);
  std::normal_distribution<float> n(0.0f, 0.1f);
  for (float& v : y.pixels) v = std::min(1.0f, std::max(0.0f, 0.7f * v + 0.1f + n(rng)));
  SsimOptions fixed;
  fixed.data_range = 1.0;
  const double s1 = ssim(x.view(), y.view(), fixed);
  EXPECT_NEAR(s1, slow_ssim(x, y, 1.0), 1e-12);
  EXPECT_GT(s1, 0.05);
  EXPECT_LT(s1, 0.95);
  // Default: data range from the inputs, max(max − min) of the two images (nerfstudio's call).
  auto range = [](const ImageRGB& im) {
    const auto [lo, hi] = std::minmax_element(im.pixels.begin(), im.pixels.end());
    return double(*hi) - double(*lo);
  };
  const double r = std::max(range(x), range(y));
  EXPECT_LT(r, 1.0);
  EXPECT_NEAR(ssim(x.view(), y.view()), slow_ssim(x, y, r), 1e-12);
  EXPECT_NE(ssim(x.view(), y.view()), s1);
  // Symmetric, as nerfstudio passes (gt, pred).
  EXPECT_NEAR(ssim(y.view(), x.view()), ssim(x.view(), y.view()), 1e-12);
  // Without the crop (torchmetrics after PR #2721): the whole reflect-padded map.
  SsimOptions full = fixed;
  full.crop_border = false;
  EXPECT_NEAR(ssim(x.view(), y.view(), full), slow_ssim(x, y, 1.0, false), 1e-12);
  EXPECT_NE(ssim(x.view(), y.view(), full), s1);
  const ImageRGB sx = random_image(7, 9, 3, 8), sy = random_image(7, 9, 3, 9);  // 6..10 px: ok
  EXPECT_NEAR(ssim(sx.view(), sy.view(), full), slow_ssim(sx, sy, 1.0, false), 1e-12);
  // Grey (one channel) images work the same way.
  const ImageRGB gx = random_image(11, 14, 1, 6), gy = random_image(11, 14, 1, 7);
  EXPECT_NEAR(ssim(gx.view(), gy.view(), fixed), slow_ssim(gx, gy, 1.0), 1e-12);
}

TEST(Ssim, TooSmallOrMismatchedImagesAreUserErrors) {
  const ImageRGB small(10, 30, 3, 0.5f), ok(11, 11, 3, 0.5f), other(11, 12, 3, 0.5f);
  EXPECT_THROW(ssim(small.view(), small.view()), Error);
  EXPECT_THROW(ssim(ok.view(), other.view()), Error);
  SsimOptions o;
  o.data_range = 1.0;
  EXPECT_NEAR(ssim(ok.view(), ok.view(), o), 1.0, 1e-12);
  o.crop_border = false;
  EXPECT_NO_THROW(ssim(small.view(), small.view(), o));
  const ImageRGB tiny(5, 30, 3, 0.5f);  // reflect padding by 5 needs more than 5 rows
  EXPECT_THROW(ssim(tiny.view(), tiny.view(), o), Error);
}

}  // namespace
}  // namespace neraf::metrics
