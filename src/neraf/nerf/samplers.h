#pragma once
// Sample placement along rays (nerfstudio UniformLinDispPiecewiseSampler, PDFSampler and the
// ProposalNetworkSampler's schedules). Samples are contiguous intervals, so a ray's samples are
// stored as S + 1 bin edges, both in "spacing" space s ∈ [0, 1] (what the PDF sampler and the
// interlevel/distortion losses work in) and as euclidean distances t along the unit direction.
//
// Spacing (UniformLinDisp piecewise): g(t) = t/2 for t < 1, 1 − 1/(2t) otherwise (uniform up to
// distance 1, uniform in disparity beyond); s maps to t = g⁻¹(s·g(far) + (1 − s)·g(near)).
#include <torch/types.h>

#include <cstdint>

namespace at {
class Generator;
}

namespace neraf::nerf {

struct RaySamples {
  torch::Tensor sdist;  // [R, S + 1] spacing-space bin edges, increasing, in [0, 1]
  torch::Tensor tdist;  // [R, S + 1] euclidean bin edges (distance along the unit direction)

  int64_t num_samples() const { return sdist.size(1) - 1; }
  torch::Tensor starts() const;     // [R, S]
  torch::Tensor ends() const;       // [R, S]
  torch::Tensor deltas() const;     // [R, S] ends − starts
  torch::Tensor midpoints() const;  // [R, S] (starts + ends)/2: where the field is evaluated
};

// The spacing function g and its inverse (elementwise).
torch::Tensor lindisp_piecewise_spacing(const torch::Tensor& t);
torch::Tensor lindisp_piecewise_spacing_inv(const torch::Tensor& s);
// s: [R, K] → t: [R, K] for nears/fars [R].
torch::Tensor spacing_to_euclidean(const torch::Tensor& s, const torch::Tensor& nears,
                                   const torch::Tensor& fars);

// Which rows of a larger batch the R rays are (data-parallel training, train/distributed.h):
// the randoms are drawn for all `total` rows and rows [begin, begin + R) are used, so a rank's
// slice of a global batch gets exactly the jitter one process would give those rays.
// total = 0: the R rays are the whole batch.
struct JitterRows {
  int64_t total = 0;
  int64_t begin = 0;
};

// Initial sampler: edges linspace(0, 1, S + 1). With `jitter`, each edge moves uniformly within
// its half-cells (between neighbouring bin centres; the first/last stay in [0, ½ bin] /
// [1 − ½ bin, 1]) by one random offset per ray (single_jitter) or per edge; randoms come from
// `gen` (CPU generator) and are moved to the device of `nears`.
RaySamples uniform_lindisp_samples(const torch::Tensor& nears, const torch::Tensor& fars,
                                   int64_t num_samples, bool jitter, bool single_jitter,
                                   at::Generator* gen, JitterRows rows = {});

// PDF resampling in spacing space (nerfstudio PDFSampler, include_original=False):
// weights + histogram_padding, then padding so that Σ ≥ eps, cdf = min(1, cumsum); u on
// num_samples + 1 regular positions: stratified (+ one jitter per ray or per position, training)
// or the cell midpoints (eval); inverted with searchsorted(right) and linear interpolation inside
// the source bins. The result is detached (no gradient flows through sample positions).
// prev: source samples; weights: [R, S_prev] (already annealed).
RaySamples pdf_samples(const RaySamples& prev, const torch::Tensor& weights,
                       const torch::Tensor& nears, const torch::Tensor& fars, int64_t num_samples,
                       bool stratified, bool single_jitter, double histogram_padding, double eps,
                       at::Generator* gen, JitterRows rows = {});

// Proposal weight annealing exponent: b·x/((b − 1)·x + 1), x = clip(step/max_iters, 0, 1).
double proposal_weight_anneal(int64_t step, double slope, int64_t max_iters);

// The proposal networks' update schedule: sched(step) = clip(interp(step, [0, warmup],
// [0, update_every]), 1, update_every). Called once per training step with the counter value
// after the previous step (start: 0): the counter is incremented, then the proposal nets train
// (run with gradients) iff counter > sched(step) or step < 10, in which case it resets to 0.
struct ProposalUpdate {
  bool update;                 // run the proposal networks with gradients this step
  int64_t steps_since_update;  // the counter to pass to the next call
};
ProposalUpdate proposal_update(int64_t step, int64_t steps_since_update, int update_every,
                               int warmup);

}  // namespace neraf::nerf
