#include "neraf/infer/audio_field.h"

#include <torch/torch.h>

#include "neraf/dsp/griffin_lim.h"

namespace neraf::infer {

torch::Tensor AudioField::predict_log_stft(const geometry::Vec3& mic, const geometry::Vec3& src,
                                           double yaw_deg) const {
  const torch::Tensor m = torch::tensor({mic.x, mic.y, mic.z}, torch::kFloat64).view({1, 3});
  const torch::Tensor s = torch::tensor({src.x, src.y, src.z}, torch::kFloat64).view({1, 3});
  return predict_log_stft_batch(m, s, torch::tensor({yaw_deg}, torch::kFloat64))[0];
}

std::vector<std::vector<float>> AudioField::predict_waveform(const geometry::Vec3& mic,
                                                             const geometry::Vec3& src,
                                                             double yaw_deg, uint64_t seed,
                                                             int64_t length) const {
  return griffin_lim_channels(log_stft_to_magnitude(predict_log_stft(mic, src, yaw_deg)),
                              info().stft, seed, length);
}

std::vector<std::vector<float>> griffin_lim_channels(const torch::Tensor& magnitude,
                                                     const dsp::StftParams& stft, uint64_t seed,
                                                     int64_t length) {
  TORCH_CHECK(magnitude.dim() == 3, "griffin_lim_channels: expected [C, F, T]");
  const torch::Tensor m = magnitude.to(torch::kFloat32).contiguous();
  std::vector<dsp::Matrix> mats;
  for (int64_t c = 0; c < m.size(0); ++c) {
    dsp::Matrix x;
    x.rows = static_cast<int>(m.size(1));
    x.cols = static_cast<int>(m.size(2));
    const float* p = m[c].data_ptr<float>();
    x.data.assign(p, p + m.size(1) * m.size(2));
    mats.push_back(std::move(x));
  }
  dsp::GriffinLimOptions o;
  o.seed = seed;
  std::vector<std::vector<float>> out = dsp::griffin_lim(mats, stft, o);
  if (length > 0)
    for (auto& ch : out) ch.resize(static_cast<size_t>(length), 0.0f);
  return out;
}

}  // namespace neraf::infer
