#include "neraf/acoustic/grid_sampler.h"

#include <torch/torch.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "neraf/util/error.h"

namespace neraf::acoustic {

using torch::indexing::Slice;

ViewDirections parse_view_directions(const std::string& name) {
  if (name == "spread") return ViewDirections::kSpread;
  if (name == "reference") return ViewDirections::kReference;
  throw Error("grid view_directions: unknown value '" + name + "': use 'spread' or 'reference'");
}

std::string to_string(ViewDirections directions) {
  return directions == ViewDirections::kSpread ? "spread" : "reference";
}

torch::Tensor fibonacci_sphere_directions(int64_t n) {
  TORCH_CHECK(n >= 1, "fibonacci_sphere_directions: n must be positive");
  auto out = torch::empty({n, 3}, torch::kFloat64);
  auto a = out.accessor<double, 2>();
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  for (int64_t i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * static_cast<double>(i) + 1.0) / static_cast<double>(n);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden_angle * static_cast<double>(i);
    a[i][0] = r * std::cos(phi);
    a[i][1] = r * std::sin(phi);
    a[i][2] = z;
  }
  return out.to(torch::kFloat32);
}

torch::Tensor reference_view_directions() {
  const double phis[3] = {M_PI / 3.0, 0.0, -M_PI};
  auto out = torch::empty({18, 3}, torch::kFloat64);
  auto a = out.accessor<double, 2>();
  int64_t row = 0;
  for (double phi : phis) {
    for (int k = 0; k < 6; ++k) {
      const double theta = k * M_PI / 3.0;
      // Quirk of the published code kept verbatim: sinθ used twice, φ never enters z.
      a[row][0] = std::cos(phi) * std::sin(theta);
      a[row][1] = std::cos(phi) * std::sin(theta);
      a[row][2] = std::sin(theta);
      ++row;
    }
  }
  return out.to(torch::kFloat32);
}

torch::Tensor grid_cell_centres_1d(int64_t resolution) {
  return (torch::arange(resolution, torch::kFloat64) + 0.5)
      .div_(static_cast<double>(resolution))
      .to(torch::kFloat32);
}

namespace {

// Flat cell indices [n] → (i, j, k) index tensors, x-major, z fastest.
std::array<torch::Tensor, 3> split_flat_index(const torch::Tensor& flat, int64_t s) {
  return {torch::div(flat, s * s, "floor"), torch::remainder(torch::div(flat, s, "floor"), s),
          torch::remainder(flat, s)};
}

torch::Tensor centres_of(const torch::Tensor& flat, int64_t s) {
  const auto ijk = split_flat_index(flat, s);
  return (torch::stack({ijk[0], ijk[1], ijk[2]}, 1).to(torch::kFloat64) + 0.5)
      .div_(static_cast<double>(s))
      .to(torch::kFloat32);  // [n, 3]
}

torch::Tensor wrapped_range(int64_t first, int64_t count, int64_t total) {
  return torch::remainder(torch::arange(first, first + count, torch::kInt64), total);
}

}  // namespace

torch::Tensor grid_cell_centres(int64_t resolution, int64_t first, int64_t count) {
  const int64_t total = resolution * resolution * resolution;
  return centres_of(wrapped_range(first, count, total), resolution);
}

GridSamplerImpl::GridSamplerImpl(GridSamplerOptions options) : options_(options) {
  require(options_.resolution >= 2,
          "grid resolution: must be at least 2 (cpu preset 32, paper 128)");
  require(options_.cells_per_update >= 1, "grid cells_per_update: must be positive (paper 4096)");
  require(options_.delta > 0, "grid delta: must be positive (reference 0.01)");
  if (options_.view_directions == ViewDirections::kReference) {
    directions_ = reference_view_directions();
  } else {
    require(options_.num_directions >= 1, "grid num_directions: must be positive (default 18)");
    directions_ = fibonacci_sphere_directions(options_.num_directions);
  }
  const int64_t s = options_.resolution;
  grid_ = register_buffer("grid", torch::zeros({7, s, s, s}, torch::kFloat32));
  pointer_ = register_buffer("pointer", torch::zeros({}, torch::kInt64));
  reset();
}

void GridSamplerImpl::reset() {
  torch::NoGradGuard no_grad;
  grid_.detach_();
  const int64_t s = options_.resolution;
  grid_.zero_();
  const auto c = grid_cell_centres_1d(s).to(grid_.device());
  grid_[4].copy_(c.view({s, 1, 1}).expand({s, s, s}));
  grid_[5].copy_(c.view({1, s, 1}).expand({s, s, s}));
  grid_[6].copy_(c.view({1, 1, s}).expand({s, s, s}));
  pointer_.zero_();
}

int64_t GridSamplerImpl::pointer() const { return pointer_.item<int64_t>(); }

torch::Tensor GridSamplerImpl::query_cells(const FieldQueryFn& field,
                                           const torch::Tensor& u) const {
  const int64_t n = u.size(0);
  const auto dirs = directions_.to(u.device());
  const int64_t d = dirs.size(0);
  // Every cell is queried with every direction: [n·D, 3], cell-major.
  const auto u_rep = u.unsqueeze(1).expand({n, d, 3}).reshape({n * d, 3});
  const auto dirs_rep = dirs.unsqueeze(0).expand({n, d, 3}).reshape({n * d, 3});
  auto [density, rgb] = field(u_rep, dirs_rep);
  TORCH_CHECK(density.numel() == n * d, "GridSampler: field returned ", density.numel(),
              " densities for ", n * d, " samples");
  TORCH_CHECK(rgb.numel() == n * d * 3, "GridSampler: field returned rgb of shape ", rgb.sizes());
  const auto density_mean = density.reshape({n, d}).to(torch::kFloat32).mean(1);  // [n]
  const auto rgb_mean = rgb.reshape({n, d, 3}).to(torch::kFloat32).mean(1);       // [n, 3]
  const auto alpha = torch::clamp(1.0 - torch::exp(-options_.delta * density_mean), 0.0, 1.0);
  return torch::cat({rgb_mean.t(), alpha.unsqueeze(0)}, 0);  // [4, n]
}

torch::Tensor GridSamplerImpl::update(const FieldQueryFn& field) {
  if (!is_training()) return torch::empty({0}, torch::kInt64);
  const int64_t s = options_.resolution;
  const int64_t total = s * s * s;
  const int64_t n = std::min(options_.cells_per_update, total);
  const int64_t first = pointer();
  const auto flat = wrapped_range(first, n, total).to(grid_.device());  // [n]
  const auto values = query_cells(field, centres_of(flat, s));          // [4, n]
  // Cut last update's autograd path, then write in place: only these n cells stay differentiable.
  grid_.detach_();
  const auto ijk = split_flat_index(flat, s);
  grid_.index_put_({Slice(0, 4), ijk[0], ijk[1], ijk[2]}, values.to(grid_.dtype()));
  pointer_.fill_((first + n) % total);
  return flat;
}

void GridSamplerImpl::refresh_all(const FieldQueryFn& field, int64_t chunk) {
  require(chunk >= 1, "grid refresh chunk: must be positive");
  torch::NoGradGuard no_grad;
  grid_.detach_();
  const int64_t s = options_.resolution;
  const int64_t total = s * s * s;
  for (int64_t first = 0; first < total; first += chunk) {
    const int64_t n = std::min(chunk, total - first);
    const auto flat = torch::arange(first, first + n, torch::kInt64).to(grid_.device());
    const auto values = query_cells(field, centres_of(flat, s));
    const auto ijk = split_flat_index(flat, s);
    grid_.index_put_({Slice(0, 4), ijk[0], ijk[1], ijk[2]}, values.to(grid_.dtype()));
  }
}

}  // namespace neraf::acoustic
