#include "neraf/infer/image_output.h"

#include <torch/torch.h>

#include "neraf/io/png.h"

namespace neraf::infer {

torch::Tensor to_uint8(const torch::Tensor& image) {
  return (image.to(torch::kFloat32).clamp(0.0, 1.0) * 255.0).round().to(torch::kUInt8);
}

torch::Tensor viridis(const torch::Tensor& t) {
  static const float kStops[9][3] = {
      {0.267004f, 0.004874f, 0.329415f}, {0.282623f, 0.140926f, 0.457517f},
      {0.229739f, 0.322361f, 0.545706f}, {0.172719f, 0.448791f, 0.557885f},
      {0.127568f, 0.566949f, 0.550556f}, {0.134692f, 0.658636f, 0.517649f},
      {0.369214f, 0.788888f, 0.382914f}, {0.688944f, 0.865448f, 0.182725f},
      {0.993248f, 0.906157f, 0.143936f}};
  const torch::Tensor stops =
      torch::from_blob(const_cast<float*>(&kStops[0][0]), {9, 3}, torch::kFloat32).clone();
  const torch::Tensor x = t.to(torch::kFloat32).clamp(0.0, 1.0).reshape({-1}) * 8.0;
  const torch::Tensor lo = x.floor().clamp(0, 7).to(torch::kInt64);
  const torch::Tensor f = (x - lo.to(torch::kFloat32)).unsqueeze(-1);
  const torch::Tensor a = stops.index_select(0, lo);
  const torch::Tensor b = stops.index_select(0, lo + 1);
  std::vector<int64_t> shape = t.sizes().vec();
  shape.push_back(3);
  return (a * (1.0 - f) + b * f).view(shape);
}

void write_png(const std::string& path, const torch::Tensor& image) {
  TORCH_CHECK(image.dim() == 3 && (image.size(2) == 3 || image.size(2) == 1),
              "write_png: expected [H, W, 3] or [H, W, 1]");
  const torch::Tensor u8 =
      (image.scalar_type() == torch::kUInt8 ? image : to_uint8(image)).cpu().contiguous();
  io::write_png(path, static_cast<int>(u8.size(1)), static_cast<int>(u8.size(0)),
                static_cast<int>(u8.size(2)), u8.data_ptr<uint8_t>());
}

}  // namespace neraf::infer
