#include "neraf/nerf/sh_encoding.h"

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <algorithm>

namespace neraf::nerf {
namespace {

// Normalisation constants of the real SH (closed forms in the comments), tcnn's signs applied
// where the polynomials are evaluated.
constexpr double kC0 = 0.28209479177387814;   // 1/(2√π)
constexpr double kC1 = 0.48860251190291987;   // √3/(2√π)
constexpr double kC2a = 1.0925484305920792;   // √15/(2√π)
constexpr double kC2b = 0.94617469575755997;  // 3√5/(4√π)
constexpr double kC2c = 0.31539156525251999;  // √5/(4√π)
constexpr double kC2d = 0.54627421529603959;  // √15/(4√π)
constexpr double kC3a = 0.59004358992664352;  // √70/(8√π)
constexpr double kC3b = 2.8906114426405538;   // √105/(2√π)
constexpr double kC3c = 0.45704579946446572;  // √42/(8√π)
constexpr double kC3d = 0.3731763325901154;   // √7/(4√π)
constexpr double kC3e = 1.4453057213202769;   // √105/(4√π)

template <typename T>
inline void sh_values(T x, T y, T z, T* o) {
  const T xy = x * y, xz = x * z, yz = y * z, x2 = x * x, y2 = y * y, z2 = z * z;
  o[0] = T(kC0);
  o[1] = -T(kC1) * y;
  o[2] = T(kC1) * z;
  o[3] = -T(kC1) * x;
  o[4] = T(kC2a) * xy;
  o[5] = -T(kC2a) * yz;
  o[6] = T(kC2b) * z2 - T(kC2c);
  o[7] = -T(kC2a) * xz;
  o[8] = T(kC2d) * x2 - T(kC2d) * y2;
  o[9] = T(kC3a) * y * (T(-3) * x2 + y2);
  o[10] = T(kC3b) * xy * z;
  o[11] = T(kC3c) * y * (T(1) - T(5) * z2);
  o[12] = T(kC3d) * z * (T(5) * z2 - T(3));
  o[13] = T(kC3c) * x * (T(1) - T(5) * z2);
  o[14] = T(kC3e) * z * (x2 - y2);
  o[15] = T(kC3a) * x * (-x2 + T(3) * y2);
}

// ∂Y_k/∂(x, y, z) contracted with g_k, for k < count.
template <typename T>
inline void sh_vjp(T x, T y, T z, const T* g, int count, T* d) {
  T dx = 0, dy = 0, dz = 0;
  const T x2 = x * x, y2 = y * y, z2 = z * z;
  if (count > 1) {
    dy -= T(kC1) * g[1];
    dz += T(kC1) * g[2];
    dx -= T(kC1) * g[3];
  }
  if (count > 4) {
    dx += T(kC2a) * y * g[4];
    dy += T(kC2a) * x * g[4];
    dy -= T(kC2a) * z * g[5];
    dz -= T(kC2a) * y * g[5];
    dz += T(2 * kC2b) * z * g[6];
    dx -= T(kC2a) * z * g[7];
    dz -= T(kC2a) * x * g[7];
    dx += T(2 * kC2d) * x * g[8];
    dy -= T(2 * kC2d) * y * g[8];
  }
  if (count > 9) {
    dx += T(-6 * kC3a) * x * y * g[9];  // Y9 = a(−3x²y + y³)
    dy += T(3 * kC3a) * (y2 - x2) * g[9];
    dx += T(kC3b) * y * z * g[10];  // Y10 = b·xyz
    dy += T(kC3b) * x * z * g[10];
    dz += T(kC3b) * x * y * g[10];
    dy += T(kC3c) * (T(1) - T(5) * z2) * g[11];  // Y11 = c·y(1 − 5z²)
    dz += T(-10 * kC3c) * y * z * g[11];
    dz += T(kC3d) * (T(15) * z2 - T(3)) * g[12];  // Y12 = d(5z³ − 3z)
    dx += T(kC3c) * (T(1) - T(5) * z2) * g[13];   // Y13 = c·x(1 − 5z²)
    dz += T(-10 * kC3c) * x * z * g[13];
    dx += T(2 * kC3e) * x * z * g[14];  // Y14 = e·z(x² − y²)
    dy += T(-2 * kC3e) * y * z * g[14];
    dz += T(kC3e) * (x2 - y2) * g[14];
    dx += T(3 * kC3a) * (y2 - x2) * g[15];  // Y15 = a(−x³ + 3xy²)
    dy += T(6 * kC3a) * x * y * g[15];
  }
  d[0] = dx;
  d[1] = dy;
  d[2] = dz;
}

constexpr int64_t kMinPointsPerThread = 4096;

int threads_for(int64_t n, int num_threads) {
  const int64_t useful = std::max<int64_t>(1, n / kMinPointsPerThread);
  return static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(num_threads, useful)));
}

void check_dirs(const torch::Tensor& dirs, int degree) {
  TORCH_CHECK(dirs.defined(), "sh_encode: dirs is undefined");
  TORCH_CHECK(dirs.dim() == 2 && dirs.size(1) == 3, "sh_encode: dirs must be [N, 3], got ",
              dirs.sizes());
  TORCH_CHECK(degree >= 1 && degree <= 4, "sh_encode: degree must be in [1, 4], got ", degree);
  TORCH_CHECK(dirs.scalar_type() == torch::kFloat32 || dirs.scalar_type() == torch::kFloat64,
              "sh_encode: dirs must be float32 or float64, got ", dirs.scalar_type());
}

using torch::autograd::AutogradContext;
using torch::autograd::variable_list;

class ShFunction : public torch::autograd::Function<ShFunction> {
 public:
  static torch::Tensor forward(AutogradContext* ctx, const torch::Tensor& dirs_in, int64_t degree) {
    const torch::Tensor dirs = dirs_in.contiguous();
    const int64_t n = dirs.size(0);
    torch::Tensor out = torch::empty({n, degree * degree}, dirs.options());
    const int nt = at::get_num_threads();
    if (dirs.scalar_type() == torch::kFloat32) {
      sh_forward_cpu<float>(dirs.data_ptr<float>(), n, static_cast<int>(degree),
                            out.data_ptr<float>(), nt);
    } else {
      sh_forward_cpu<double>(dirs.data_ptr<double>(), n, static_cast<int>(degree),
                             out.data_ptr<double>(), nt);
    }
    ctx->save_for_backward({dirs});
    ctx->saved_data["degree"] = degree;
    return out;
  }

  static variable_list backward(AutogradContext* ctx, variable_list grads) {
    const torch::Tensor dirs = ctx->get_saved_variables()[0];
    const int degree = static_cast<int>(ctx->saved_data["degree"].toInt());
    const torch::Tensor g = grads[0].contiguous();
    const int64_t n = dirs.size(0);
    torch::Tensor grad_dirs = torch::empty({n, 3}, dirs.options());
    const int nt = at::get_num_threads();
    if (dirs.scalar_type() == torch::kFloat32) {
      sh_backward_cpu<float>(dirs.data_ptr<float>(), n, degree, g.data_ptr<float>(),
                             grad_dirs.data_ptr<float>(), nt);
    } else {
      sh_backward_cpu<double>(dirs.data_ptr<double>(), n, degree, g.data_ptr<double>(),
                              grad_dirs.data_ptr<double>(), nt);
    }
    return {grad_dirs, torch::Tensor()};
  }
};

}  // namespace

template <typename T>
void sh_forward_cpu(const T* dirs, int64_t n, int degree, T* out, int num_threads) {
  const int count = degree * degree;
#pragma omp parallel for schedule(static) num_threads(threads_for(n, num_threads))
  for (int64_t i = 0; i < n; ++i) {
    T v[16];
    sh_values(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2], v);
    T* o = out + i * count;
    for (int k = 0; k < count; ++k) o[k] = v[k];
  }
}

template <typename T>
void sh_backward_cpu(const T* dirs, int64_t n, int degree, const T* grad_out, T* grad_dirs,
                     int num_threads) {
  const int count = degree * degree;
#pragma omp parallel for schedule(static) num_threads(threads_for(n, num_threads))
  for (int64_t i = 0; i < n; ++i) {
    sh_vjp(dirs[3 * i], dirs[3 * i + 1], dirs[3 * i + 2], grad_out + i * count, count,
           grad_dirs + 3 * i);
  }
}

template void sh_forward_cpu<float>(const float*, int64_t, int, float*, int);
template void sh_forward_cpu<double>(const double*, int64_t, int, double*, int);
template void sh_backward_cpu<float>(const float*, int64_t, int, const float*, float*, int);
template void sh_backward_cpu<double>(const double*, int64_t, int, const double*, double*, int);

torch::Tensor sh_encode(const torch::Tensor& dirs, int degree) {
  check_dirs(dirs, degree);
  if (!dirs.device().is_cpu()) return sh_encode_reference(dirs, degree);
  return ShFunction::apply(dirs, static_cast<int64_t>(degree));
}

torch::Tensor sh_encode_reference(const torch::Tensor& dirs, int degree) {
  check_dirs(dirs, degree);
  const torch::Tensor x = dirs.select(1, 0), y = dirs.select(1, 1), z = dirs.select(1, 2);
  const torch::Tensor xy = x * y, xz = x * z, yz = y * z, x2 = x * x, y2 = y * y, z2 = z * z;
  std::vector<torch::Tensor> cols;
  cols.push_back(torch::full_like(x, kC0));
  if (degree > 1) {
    cols.push_back(-kC1 * y);
    cols.push_back(kC1 * z);
    cols.push_back(-kC1 * x);
  }
  if (degree > 2) {
    cols.push_back(kC2a * xy);
    cols.push_back(-kC2a * yz);
    cols.push_back(kC2b * z2 - kC2c);
    cols.push_back(-kC2a * xz);
    cols.push_back(kC2d * x2 - kC2d * y2);
  }
  if (degree > 3) {
    cols.push_back(kC3a * y * (-3 * x2 + y2));
    cols.push_back(kC3b * xy * z);
    cols.push_back(kC3c * y * (1 - 5 * z2));
    cols.push_back(kC3d * z * (5 * z2 - 3));
    cols.push_back(kC3c * x * (1 - 5 * z2));
    cols.push_back(kC3e * z * (x2 - y2));
    cols.push_back(kC3a * x * (-x2 + 3 * y2));
  }
  return torch::stack(cols, 1);  // [N, degree²]
}

torch::Tensor sh_encode_tcnn_input(const torch::Tensor& v, int degree) {
  return sh_encode(v * 2 - 1, degree);
}

}  // namespace neraf::nerf
