#include "neraf/acoustic/positional_encoding.h"

#include <torch/torch.h>

#include <cmath>

namespace neraf::acoustic {

int64_t nerf_encoding_dim(const NerfEncodingOptions& options) {
  return options.in_dim * options.num_frequencies * 2 +
         (options.include_input ? options.in_dim : 0);
}

torch::Tensor nerf_encoding_frequencies(const NerfEncodingOptions& options, torch::Dtype dtype) {
  // The reference builds `2 ** torch.linspace(min, max, n)` in the default dtype (float32): keep
  // that rounding so float64 encodings match it exactly.
  const auto exps = torch::linspace(options.min_freq_exp, options.max_freq_exp,
                                    options.num_frequencies, torch::dtype(torch::kFloat32));
  return torch::pow(2.0, exps).to(dtype);
}

torch::Tensor nerf_encode(const torch::Tensor& x, const NerfEncodingOptions& options) {
  TORCH_CHECK(x.dim() >= 1 && x.size(-1) == options.in_dim, "nerf_encode: expected [..., ",
              options.in_dim, "], got ", x.sizes());
  TORCH_CHECK(x.is_floating_point(), "nerf_encode: floating-point input required");
  const auto freqs = nerf_encoding_frequencies(options, x.scalar_type()).to(x.device());  // [n]
  const auto scaled = x * (2.0 * M_PI);  // [..., d]
  auto sizes = x.sizes().vec();
  sizes.back() = options.in_dim * options.num_frequencies;
  const auto s = (scaled.unsqueeze(-1) * freqs).reshape(sizes);    // [..., d·n], dim-major
  auto encoded = torch::sin(torch::cat({s, s + M_PI / 2.0}, -1));  // [..., 2·d·n]
  if (options.include_input) encoded = torch::cat({encoded, x}, -1);
  return encoded;
}

}  // namespace neraf::acoustic
