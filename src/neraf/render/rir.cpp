#include "neraf/render/rir.h"

#include <torch/torch.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "neraf/infer/audio_run.h"
#include "neraf/util/error.h"

namespace neraf::render {

geometry::Vec3 parse_position(const std::string& text, const std::string& flag) {
  const std::string err =
      flag + ": expected X,Y,Z (three numbers in metres, e.g. 1.5,1.2,0.9), got \"" + text + "\"";
  std::vector<double> values;
  size_t start = 0;
  for (;;) {
    const size_t comma = text.find(',', start);
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const char* begin = part.c_str();
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(begin, &end);
    require(end != begin && errno == 0 && std::isfinite(v), err);
    while (*end == ' ' || *end == '\t') ++end;
    require(*end == '\0', err);
    values.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  require(values.size() == 3, err);
  return {values[0], values[1], values[2]};
}

bool inside_open_box(const geometry::Vec3& p, const data::Aabb& box) {
  for (int a = 0; a < 3; ++a) {
    if (!(p[a] > box.min[a] && p[a] < box.max[a])) return false;
  }
  return true;
}

io::AudioBuffer rir_from_log_stft(const torch::Tensor& log_stft, const dsp::StftParams& stft,
                                  int sample_rate, const RirRenderOptions& options) {
  TORCH_CHECK(log_stft.dim() == 3, "rir_from_log_stft: expected [C, F, T]");
  TORCH_CHECK(log_stft.size(1) == stft.n_freq(), "rir_from_log_stft: F does not match n_fft");
  io::AudioBuffer out;
  out.sample_rate = sample_rate;
  out.channels =
      infer::griffin_lim_channels(infer::log_stft_to_magnitude(log_stft.cpu()), stft, options.seed);
  return out;
}

io::AudioBuffer render_rir(const LogStftFn& predict, const AudioModelInfo& info,
                           const geometry::Vec3& mic, const geometry::Vec3& src, double yaw_deg,
                           const RirRenderOptions& options) {
  const auto opts = torch::TensorOptions().dtype(torch::kFloat64);
  const torch::Tensor m = torch::tensor({mic.x, mic.y, mic.z}, opts).view({1, 3});
  const torch::Tensor s = torch::tensor({src.x, src.y, src.z}, opts).view({1, 3});
  const torch::Tensor y = torch::tensor({yaw_deg}, opts);
  const torch::Tensor log_stft = predict(m, s, y);  // [1, C, F, T]
  TORCH_CHECK(log_stft.dim() == 4 && log_stft.size(0) == 1,
              "render_rir: the model returned an unexpected shape");
  return rir_from_log_stft(log_stft[0], info.stft, info.sample_rate, options);
}

}  // namespace neraf::render
