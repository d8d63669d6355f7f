#include "neraf/nerf/hash_grid.h"

#include <ATen/CPUGeneratorImpl.h>
#include <ATen/Parallel.h>

#include <string>

namespace neraf::nerf {
namespace {

using torch::autograd::AutogradContext;
using torch::autograd::variable_list;

// The saved config keys of the autograd context (the layout is rebuilt from them: microseconds).
void save_config(AutogradContext* ctx, const HashGridConfig& c) {
  ctx->saved_data["L"] = static_cast<int64_t>(c.num_levels);
  ctx->saved_data["F"] = static_cast<int64_t>(c.features_per_level);
  ctx->saved_data["log2T"] = static_cast<int64_t>(c.log2_hashmap_size);
  ctx->saved_data["base"] = static_cast<int64_t>(c.base_resolution);
  ctx->saved_data["max"] = static_cast<int64_t>(c.max_resolution);
}

HashGridConfig load_config(AutogradContext* ctx) {
  HashGridConfig c;
  c.num_levels = static_cast<int>(ctx->saved_data["L"].toInt());
  c.features_per_level = static_cast<int>(ctx->saved_data["F"].toInt());
  c.log2_hashmap_size = static_cast<int>(ctx->saved_data["log2T"].toInt());
  c.base_resolution = static_cast<int>(ctx->saved_data["base"].toInt());
  c.max_resolution = static_cast<int>(ctx->saved_data["max"].toInt());
  return c;
}

// The CPU op: custom kernels, table gradient always, x gradient on request.
class HashGridFunction : public torch::autograd::Function<HashGridFunction> {
 public:
  static torch::Tensor forward(AutogradContext* ctx, const torch::Tensor& x,
                               const torch::Tensor& table, const HashGridConfig& config) {
    const HashGridLayout layout = HashGridLayout::make(config);
    const torch::Tensor t = table.contiguous();
    const int64_t n = x.size(0);
    torch::Tensor out = torch::empty({n, layout.output_dim()}, t.options());
    const int nt = at::get_num_threads();
    if (t.scalar_type() == torch::kFloat32) {
      hash_grid_forward_cpu<float>(x.data_ptr<float>(), n, t.data_ptr<float>(), layout,
                                   out.data_ptr<float>(), nt);
    } else {
      hash_grid_forward_cpu<double>(x.data_ptr<double>(), n, t.data_ptr<double>(), layout,
                                    out.data_ptr<double>(), nt);
    }
    // The table values are only needed for dL/dx; not saving them otherwise keeps an in-place
    // optimizer step between forward and backward legal.
    const bool want_grad_x = x.requires_grad();
    ctx->save_for_backward({x, want_grad_x ? table : torch::Tensor()});
    ctx->saved_data["table_rows"] = t.size(0);
    save_config(ctx, config);
    return out;
  }

  static variable_list backward(AutogradContext* ctx, variable_list grads) {
    const variable_list saved = ctx->get_saved_variables();
    const torch::Tensor& x = saved[0];
    const HashGridLayout layout = HashGridLayout::make(load_config(ctx));
    const torch::Tensor grad_out = grads[0].contiguous();
    const int64_t n = x.size(0);
    const bool need_table = ctx->needs_input_grad(1);
    const bool need_x = ctx->needs_input_grad(0) && saved[1].defined();
    if (!need_table && !need_x) return {torch::Tensor(), torch::Tensor(), torch::Tensor()};

    const auto options = grad_out.options();
    // Overwritten by the kernel (zeroed level by level where it is about to be used).
    torch::Tensor grad_table = torch::empty({layout.total_entries, layout.features()}, options);
    torch::Tensor grad_x = need_x ? torch::empty({n, 3}, options) : torch::Tensor();
    torch::Tensor table = need_x ? saved[1].contiguous() : torch::Tensor();
    const int nt = at::get_num_threads();
    if (grad_out.scalar_type() == torch::kFloat32) {
      hash_grid_backward_cpu<float>(
          x.data_ptr<float>(), n, need_x ? table.data_ptr<float>() : nullptr,
          grad_out.data_ptr<float>(), layout, grad_table.data_ptr<float>(),
          need_x ? grad_x.data_ptr<float>() : nullptr, nt);
    } else {
      hash_grid_backward_cpu<double>(
          x.data_ptr<double>(), n, need_x ? table.data_ptr<double>() : nullptr,
          grad_out.data_ptr<double>(), layout, grad_table.data_ptr<double>(),
          need_x ? grad_x.data_ptr<double>() : nullptr, nt);
    }
    return {grad_x, need_table ? grad_table : torch::Tensor(), torch::Tensor()};
  }
};

void check_inputs(const torch::Tensor& x, const torch::Tensor& table,
                  const HashGridLayout& layout) {
  TORCH_CHECK(x.defined() && table.defined(), "hash_grid_encode: x and table must be defined");
  TORCH_CHECK(x.dim() == 2 && x.size(1) == 3, "hash_grid_encode: x must be [N, 3], got ",
              x.sizes());
  TORCH_CHECK(table.dim() == 2 && table.size(0) == layout.total_entries &&
                  table.size(1) == layout.features(),
              "hash_grid_encode: table must be [", layout.total_entries, ", ", layout.features(),
              "] for this layout, got ", table.sizes());
  TORCH_CHECK(table.scalar_type() == torch::kFloat32 || table.scalar_type() == torch::kFloat64,
              "hash_grid_encode: table must be float32 (or float64), got ", table.scalar_type());
  TORCH_CHECK(x.scalar_type() == table.scalar_type(), "hash_grid_encode: x must have the table's ",
              "dtype (", table.scalar_type(), "), got ", x.scalar_type());
  TORCH_CHECK(x.device() == table.device(), "hash_grid_encode: x is on ", x.device(),
              " but the table is on ", table.device());
}

}  // namespace

torch::Tensor hash_grid_encode(const torch::Tensor& x, const torch::Tensor& table,
                               const HashGridLayout& layout) {
  check_inputs(x, table, layout);
  // The single dispatch point: a CUDA build would route its own kernel here.
  if (!x.device().is_cpu()) return hash_grid_encode_reference(x, table, layout);
  TORCH_CHECK(x.is_contiguous(), "hash_grid_encode: x must be contiguous (call .contiguous())");
  return HashGridFunction::apply(x, table, layout.config);
}

torch::Tensor hash_grid_encode_reference(const torch::Tensor& x, const torch::Tensor& table,
                                         const HashGridLayout& layout) {
  check_inputs(x, table, layout);
  const int64_t n = x.size(0);
  const int L = layout.num_levels(), F = layout.features();
  // Per level: the global table rows [N, 8] and trilinear weights [N, 8] of the 8 corners.
  std::vector<torch::Tensor> rows, weights;
  for (int l = 0; l < L; ++l) {
    // tcnn computes fma(x, scale, 0.5) in float: the exact product and sum in double, rounded once
    // to the input dtype, give the same value.
    torch::Tensor pos = x.to(torch::kFloat64) * static_cast<double>(layout.scales[l]) + 0.5;
    pos = pos.to(x.scalar_type());                    // [N, 3]
    const torch::Tensor grid = pos.floor().detach();  // [N, 3]
    const torch::Tensor frac = pos - grid;            // [N, 3], carries dL/dx
    const torch::Tensor g = grid.to(torch::kInt64);   // signed; wrapped to uint32 below
    std::vector<torch::Tensor> level_rows, level_weights;
    for (int c = 0; c < 8; ++c) {
      const int64_t b[3] = {c & 1, (c >> 1) & 1, c >> 2};
      const torch::Tensor gx = g.select(1, 0) + b[0];
      const torch::Tensor gy = g.select(1, 1) + b[1];
      const torch::Tensor gz = g.select(1, 2) + b[2];
      torch::Tensor idx;
      if (layout.dense[l]) {
        const int64_t res = layout.resolutions[l];
        idx = torch::bitwise_and(gx + gy * res + gz * (res * res), int64_t{0xFFFFFFFF});
        idx = torch::remainder(idx, layout.sizes[l]);
      } else {
        // The low 32 bits of these int64 products are tcnn's uint32 products.
        idx = torch::bitwise_xor(torch::bitwise_xor(gx, gy * int64_t{2654435761LL}),
                                 gz * int64_t{805459861LL});
        idx = torch::bitwise_and(idx, layout.sizes[l] - 1);
      }
      level_rows.push_back(idx + layout.offsets[l]);
      torch::Tensor w = torch::ones({n}, x.options());
      for (int d = 0; d < 3; ++d) {
        const torch::Tensor f = frac.select(1, d);
        w = w * (b[d] ? f : 1 - f);
      }
      level_weights.push_back(w);
    }
    rows.push_back(torch::stack(level_rows, 1));
    weights.push_back(torch::stack(level_weights, 1));
  }
  // One gather for everything (one gradient buffer for the table in the backward pass).
  const torch::Tensor all_rows = torch::stack(rows, 0).reshape({-1});  // [L·N·8]
  const torch::Tensor vals = table.index_select(0, all_rows).reshape({L, n, 8, F});
  const torch::Tensor w = torch::stack(weights, 0).to(table.scalar_type());  // [L, N, 8]
  const torch::Tensor out = (w.unsqueeze(3) * vals).sum(2);                  // [L, N, F]
  return out.permute({1, 0, 2}).reshape({n, L * F});                         // [N, L·F]
}

HashGridImpl::HashGridImpl(HashGridConfig config, uint64_t seed)
    : layout_(HashGridLayout::make(config)) {
  // Own generator: the initial table depends on `seed` only, not on the global RNG state.
  at::Generator gen = at::make_generator<at::CPUGeneratorImpl>(seed);
  torch::Tensor t = torch::empty({layout_.total_entries, layout_.features()}, torch::kFloat32);
  t.uniform_(-1e-4, 1e-4, gen);
  table = register_parameter("table", t);
}

torch::Tensor HashGridImpl::forward(torch::Tensor x) { return hash_grid_encode(x, table, layout_); }

}  // namespace neraf::nerf
