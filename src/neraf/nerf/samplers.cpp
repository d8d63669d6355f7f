#include "neraf/nerf/samplers.h"

#include <ATen/core/Generator.h>
#include <torch/torch.h>

#include <algorithm>

namespace neraf::nerf {

torch::Tensor RaySamples::starts() const { return tdist.slice(1, 0, -1); }
torch::Tensor RaySamples::ends() const { return tdist.slice(1, 1); }
torch::Tensor RaySamples::deltas() const { return ends() - starts(); }
torch::Tensor RaySamples::midpoints() const { return (starts() + ends()) * 0.5; }

torch::Tensor lindisp_piecewise_spacing(const torch::Tensor& t) {
  // The untaken branch is evaluated on a clamped argument so it never divides by zero.
  return torch::where(t < 1, t * 0.5, 1.0 - 0.5 / t.clamp_min(1.0));
}

torch::Tensor lindisp_piecewise_spacing_inv(const torch::Tensor& s) {
  return torch::where(s < 0.5, s * 2.0, 0.5 / (1.0 - s).clamp_min(1e-30));
}

torch::Tensor spacing_to_euclidean(const torch::Tensor& s, const torch::Tensor& nears,
                                   const torch::Tensor& fars) {
  const torch::Tensor s_near = lindisp_piecewise_spacing(nears).unsqueeze(1);  // [R, 1]
  const torch::Tensor s_far = lindisp_piecewise_spacing(fars).unsqueeze(1);
  return lindisp_piecewise_spacing_inv(s * s_far + (1.0 - s) * s_near);
}

namespace {
// Uniform [0,1) randoms [R, K] from the CPU generator, moved to `device`; with rows.total, drawn
// for all rows.total rows and rows [begin, begin + R) kept.
torch::Tensor uniform(int64_t R, int64_t K, at::Generator* gen, const torch::Device& device,
                      JitterRows rows) {
  const int64_t n = rows.total > 0 ? rows.total : R;
  TORCH_CHECK(rows.begin >= 0 && rows.begin + R <= n, "JitterRows: rows ", rows.begin, "+", R,
              " outside ", n);
  torch::Tensor r = gen ? torch::rand({n, K}, *gen, torch::kFloat32) : torch::rand({n, K});
  if (n != R) r = r.narrow(0, rows.begin, R);
  return r.to(device);
}
}  // namespace

RaySamples uniform_lindisp_samples(const torch::Tensor& nears, const torch::Tensor& fars,
                                   int64_t num_samples, bool jitter, bool single_jitter,
                                   at::Generator* gen, JitterRows rows) {
  const int64_t R = nears.size(0);
  const auto opts = nears.options().dtype(torch::kFloat32);
  torch::Tensor bins = torch::linspace(0.0, 1.0, num_samples + 1, opts).unsqueeze(0);  // [1, S+1]
  if (jitter) {
    const torch::Tensor t_rand =
        uniform(R, single_jitter ? 1 : num_samples + 1, gen, nears.device(), rows);
    const torch::Tensor centers = (bins.slice(1, 1) + bins.slice(1, 0, -1)) * 0.5;  // [1, S]
    const torch::Tensor upper = torch::cat({centers, bins.slice(1, -1)}, 1);
    const torch::Tensor lower = torch::cat({bins.slice(1, 0, 1), centers}, 1);
    bins = lower + (upper - lower) * t_rand;  // [R, S+1]
  } else {
    bins = bins.expand({R, num_samples + 1}).contiguous();
  }
  return {bins, spacing_to_euclidean(bins, nears, fars)};
}

RaySamples pdf_samples(const RaySamples& prev, const torch::Tensor& weights,
                       const torch::Tensor& nears, const torch::Tensor& fars, int64_t num_samples,
                       bool stratified, bool single_jitter, double histogram_padding, double eps,
                       at::Generator* gen, JitterRows rows) {
  torch::NoGradGuard no_grad;  // sample positions carry no gradient (nerfstudio detaches them)
  const int64_t R = weights.size(0);
  const int64_t num_bins = num_samples + 1;
  torch::Tensor w = weights.detach() + histogram_padding;  // [R, S]
  torch::Tensor w_sum = w.sum(-1, /*keepdim=*/true);
  const torch::Tensor padding = torch::relu(eps - w_sum);
  w = w + padding / w.size(-1);
  w_sum = w_sum + padding;
  const torch::Tensor pdf = w / w_sum;
  torch::Tensor cdf = torch::clamp_max(torch::cumsum(pdf, -1), 1.0);
  cdf = torch::cat({torch::zeros({R, 1}, cdf.options()), cdf}, -1).contiguous();  // [R, S+1]

  const auto opts = weights.options().dtype(torch::kFloat32);
  torch::Tensor u = torch::linspace(0.0, 1.0 - 1.0 / num_bins, num_bins, opts).unsqueeze(0);
  if (stratified) {
    const torch::Tensor r =
        uniform(R, single_jitter ? 1 : num_bins, gen, weights.device(), rows) / num_bins;
    u = u + r;
  } else {
    u = (u + 1.0 / (2 * num_bins)).expand({R, num_bins});
  }
  u = u.contiguous();  // [R, num_bins]

  const torch::Tensor& existing = prev.sdist;  // [R, S+1]
  const int64_t last = existing.size(1) - 1;
  const torch::Tensor inds = torch::searchsorted(cdf, u, /*out_int32=*/false, /*right=*/true);
  const torch::Tensor below = (inds - 1).clamp(0, last);
  const torch::Tensor above = inds.clamp(0, last);
  const torch::Tensor cdf_g0 = cdf.gather(1, below), cdf_g1 = cdf.gather(1, above);
  const torch::Tensor bins_g0 = existing.gather(1, below), bins_g1 = existing.gather(1, above);
  const torch::Tensor t =
      torch::clamp(torch::nan_to_num((u - cdf_g0) / (cdf_g1 - cdf_g0), 0.0), 0.0, 1.0);
  const torch::Tensor bins = bins_g0 + t * (bins_g1 - bins_g0);  // [R, num_bins]
  return {bins, spacing_to_euclidean(bins, nears, fars)};
}

double proposal_weight_anneal(int64_t step, double slope, int64_t max_iters) {
  const double x = std::clamp(static_cast<double>(step) / static_cast<double>(max_iters), 0.0, 1.0);
  return slope * x / ((slope - 1.0) * x + 1.0);
}

ProposalUpdate proposal_update(int64_t step, int64_t steps_since_update, int update_every,
                               int warmup) {
  const double ramp = static_cast<double>(update_every) *
                      std::clamp(static_cast<double>(step) / warmup, 0.0, 1.0);  // np.interp
  const double sched = std::clamp(ramp, 1.0, static_cast<double>(std::max(update_every, 1)));
  const int64_t counter = steps_since_update + 1;
  const bool update = static_cast<double>(counter) > sched || step < 10;
  return {update, update ? 0 : counter};
}

}  // namespace neraf::nerf
