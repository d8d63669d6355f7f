#include "neraf/metrics/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "neraf/util/error.h"

namespace neraf::metrics {

namespace {

std::string shape(const ImageView& im) {
  return std::to_string(im.height) + "x" + std::to_string(im.width) + "x" +
         std::to_string(im.channels);
}

void check_pair(const ImageView& pred, const ImageView& gt, const char* metric) {
  require(pred.height == gt.height && pred.width == gt.width && pred.channels == gt.channels,
          std::string(metric) + ": predicted image is " + shape(pred) + " but ground truth is " +
              shape(gt) + "; compare images of the same size");
  require(gt.height > 0 && gt.width > 0 && gt.channels > 0 && pred.data && gt.data,
          std::string(metric) + ": empty image");
}

double value_range(const ImageView& im) {
  const size_t n = size_t(im.height) * im.width * im.channels;
  const auto [lo, hi] = std::minmax_element(im.data, im.data + n);
  return double(*hi) - double(*lo);
}

}  // namespace

double psnr(const ImageView& pred, const ImageView& gt, double data_range) {
  check_pair(pred, gt, "PSNR");
  const size_t n = size_t(gt.height) * gt.width * gt.channels;
  double sse = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double d = double(pred.data[i]) - double(gt.data[i]);
    sse += d * d;
  }
  if (sse == 0.0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(data_range * data_range / (sse / double(n)));
}

std::vector<double> ssim_gaussian_window(double sigma) {
  require(sigma > 0.0, "SSIM: sigma must be positive");
  const int size = static_cast<int>(3.5 * sigma + 0.5) * 2 + 1;
  std::vector<double> w(size);
  double sum = 0.0;
  for (int i = 0; i < size; ++i) {
    const double d = (1.0 - size) / 2.0 + i;  // torch.arange((1 - k)/2, (1 + k)/2)
    w[i] = std::exp(-(d / sigma) * (d / sigma) / 2.0);
    sum += w[i];
  }
  for (double& v : w) v /= sum;
  return w;
}

double ssim(const ImageView& pred, const ImageView& gt, const SsimOptions& options) {
  check_pair(pred, gt, "SSIM");
  const std::vector<double> g = ssim_gaussian_window(options.sigma);
  const int k = static_cast<int>(g.size());
  const int p = (k - 1) / 2;
  const int H = gt.height, W = gt.width, C = gt.channels;
  // The crop keeps (H − 2p)·(W − 2p) positions; reflect padding itself needs p < H, W.
  const int min_side = options.crop_border ? k : p + 1;
  require(H >= min_side && W >= min_side, "SSIM: images of " + shape(gt) +
                                              " are too small for the " + std::to_string(k) + "x" +
                                              std::to_string(k) + " window; use images at least " +
                                              std::to_string(min_side) + " pixels on each side");

  const double range =
      options.data_range ? *options.data_range : std::max(value_range(pred), value_range(gt));
  const double c1 = (options.k1 * range) * (options.k1 * range);
  const double c2 = (options.k2 * range) * (options.k2 * range);

  // torchmetrics reflect-pads by p and filters (valid correlation, so the map is H×W). The
  // padded image is P(i, j) = I(reflect(i − p), reflect(j − p)), so the 2-D Gaussian separates
  // into a horizontal and a vertical pass that each read reflected indices. With the crop, every
  // kept output position (i in [p, H − p)) reads only rows i − p..i + p, all inside the image:
  // the padding never reaches the result and only the kept region is computed.
  auto reflect = [](int i, int n) { return i < 0 ? -i : (i >= n ? 2 * (n - 1) - i : i); };
  const int y0 = options.crop_border ? p : 0, y1 = options.crop_border ? H - p : H;
  const int x0 = options.crop_border ? p : 0, x1 = options.crop_border ? W - p : W;
  const int Wo = x1 - x0;
  // Five quantities per pixel, filtered horizontally: x, y, x², y², x·y. [5][H][Wo]
  std::vector<double> horiz(size_t(5) * H * Wo);
  double total = 0.0;
  for (int c = 0; c < C; ++c) {
    auto px = [&](int y, int x) { return double(pred.data[(size_t(y) * W + x) * C + c]); };
    auto gx = [&](int y, int x) { return double(gt.data[(size_t(y) * W + x) * C + c]); };
    for (int y = 0; y < H; ++y) {
      for (int xo = x0; xo < x1; ++xo) {
        double s[5] = {0, 0, 0, 0, 0};
        for (int b = 0; b < k; ++b) {
          const int x = reflect(xo + b - p, W);
          const double a = px(y, x), t = gx(y, x), wgt = g[b];
          s[0] += wgt * a;
          s[1] += wgt * t;
          s[2] += wgt * a * a;
          s[3] += wgt * t * t;
          s[4] += wgt * a * t;
        }
        for (int q = 0; q < 5; ++q) horiz[(size_t(q) * H + y) * Wo + (xo - x0)] = s[q];
      }
    }
    for (int yo = y0; yo < y1; ++yo) {
      for (int xo = 0; xo < Wo; ++xo) {
        double m[5] = {0, 0, 0, 0, 0};
        for (int a = 0; a < k; ++a) {
          const int y = reflect(yo + a - p, H);
          for (int q = 0; q < 5; ++q) m[q] += g[a] * horiz[(size_t(q) * H + y) * Wo + xo];
        }
        const double mu_p = m[0], mu_t = m[1];
        const double var_p = std::max(0.0, m[2] - mu_p * mu_p);
        const double var_t = std::max(0.0, m[3] - mu_t * mu_t);
        const double cov = m[4] - mu_p * mu_t;
        total += ((2.0 * mu_p * mu_t + c1) * (2.0 * cov + c2)) /
                 ((mu_p * mu_p + mu_t * mu_t + c1) * (var_p + var_t + c2));
      }
    }
  }
  return total / (double(y1 - y0) * Wo * C);
}

}  // namespace neraf::metrics
