#pragma once
// Image quality metrics as nerfstudio 1.1.4 evaluates Nerfacto views (neraf-reference.md §4.7):
// torchmetrics PeakSignalNoiseRatio(data_range=1.0) and structural_similarity_index_measure with
// its defaults. Images are float, interleaved [H, W, C] (RGB: C = 3), values in [0, 1].
// Computed in double precision (torchmetrics runs float32: expect agreement to ~1e-6).
#include <optional>
#include <vector>

namespace neraf::metrics {

// A non-owning view of an interleaved [height, width, channels] float image.
struct ImageView {
  const float* data = nullptr;
  int height = 0;
  int width = 0;
  int channels = 3;
};

// An owning RGB(…) image, [height, width, channels] row-major interleaved.
struct ImageRGB {
  int height = 0;
  int width = 0;
  int channels = 3;
  std::vector<float> pixels;

  ImageRGB() = default;
  ImageRGB(int h, int w, int c = 3, float value = 0.0f)
      : height(h), width(w), channels(c), pixels(size_t(h) * w * c, value) {}
  float& at(int y, int x, int c) { return pixels[(size_t(y) * width + x) * channels + c]; }
  float at(int y, int x, int c) const { return pixels[(size_t(y) * width + x) * channels + c]; }
  ImageView view() const { return {pixels.data(), height, width, channels}; }
};

// PSNR = 10·log10(data_range² / MSE) with the MSE over all H·W·C values; +inf for identical
// images. Shapes must match (neraf::Error otherwise).
double psnr(const ImageView& pred, const ImageView& gt, double data_range = 1.0);

struct SsimOptions {
  // torchmetrics' Gaussian window: its size is derived from sigma, int(3.5·σ + 0.5)·2 + 1 (= 11
  // for σ = 1.5); torchmetrics ignores kernel_size when the kernel is Gaussian.
  double sigma = 1.5;
  double k1 = 0.01;
  double k2 = 0.03;
  // Unset = torchmetrics' default, max(max−min of pred, max−min of gt) over all pixels and
  // channels: what nerfstudio's evaluation uses (it passes no data_range). Set 1.0 to fix the
  // range of [0, 1] images instead.
  std::optional<double> data_range;
  // Average only the map's inner (H − 2p)·(W − 2p) positions, as torchmetrics 1.x did until its
  // PR #2721 (merged 2024-09; the nerfstudio 1.1.4 / NeRAF era). false = the later releases, which
  // average the whole reflect-padded H×W map.
  bool crop_border = true;
};

// torchmetrics structural_similarity_index_measure (1.x, the versions nerfstudio 1.1.4 runs):
// each image is reflect-padded (mirror without repeating the edge, torch "reflect") by
// p = (window − 1)/2 on every side, filtered with the normalised separable Gaussian (valid
// correlation: the SSIM map has the original H×W size), the map's border of p pixels is cropped
// and the remaining (H − 2p)·(W − 2p)·C values are averaged. Variances are clamped at 0.
// Needs H, W >= window (> p without the crop; neraf::Error otherwise). Identical non-constant
// images give 1; with the data range taken from two constant images it is 0 and the result NaN,
// as in torchmetrics.
double ssim(const ImageView& pred, const ImageView& gt, const SsimOptions& options = {});

// The normalised 1-D Gaussian window torchmetrics builds for `sigma` (exposed for tests).
std::vector<double> ssim_gaussian_window(double sigma);

}  // namespace neraf::metrics
