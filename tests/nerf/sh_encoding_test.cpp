// Spherical-harmonics encoding: tcnn's polynomials and signs at hand-picked directions, the custom
// op against the tensor-op reference (values and gradients), finite differences, the tcnn input
// mapping, degree prefixes and orthonormality by Monte Carlo.
#include "neraf/nerf/sh_encoding.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <array>
#include <cmath>

namespace neraf::nerf {
namespace {

// The 16 polynomials transcribed from neraf-reference.md §1.2 (its 8-digit constants), in double.
std::array<double, 16> doc_formulas(double x, double y, double z) {
  return {0.28209479,
          -0.48860251 * y,
          0.48860251 * z,
          -0.48860251 * x,
          1.0925484 * x * y,
          -1.0925484 * y * z,
          0.94617470 * z * z - 0.31539157,
          -1.0925484 * x * z,
          0.54627422 * (x * x - y * y),
          0.59004359 * y * (-3 * x * x + y * y),
          2.8906114 * x * y * z,
          0.45704580 * y * (1 - 5 * z * z),
          0.37317633 * z * (5 * z * z - 3),
          0.45704580 * x * (1 - 5 * z * z),
          1.4453057 * z * (x * x - y * y),
          0.59004359 * x * (-x * x + 3 * y * y)};
}

TEST(ShEncoding, MatchesDocumentedFormulas) {
  const double s = 1.0 / std::sqrt(3.0);
  const double dirs[][3] = {{1, 0, 0}, {0, 1, 0},  {0, 0, 1},         {-1, 0, 0},
                            {s, s, s}, {s, -s, s}, {0.48, -0.6, 0.64}};
  for (const auto& d : dirs) {
    const torch::Tensor in = torch::tensor({d[0], d[1], d[2]}, torch::kFloat64).reshape({1, 3});
    const torch::Tensor out = sh_encode(in);
    ASSERT_EQ(out.sizes(), (torch::IntArrayRef{1, 16}));
    const auto expected = doc_formulas(d[0], d[1], d[2]);
    for (int k = 0; k < 16; ++k) {
      EXPECT_NEAR(out[0][k].item<double>(), expected[k], 2e-8)
          << "Y" << k << " at (" << d[0] << ", " << d[1] << ", " << d[2] << ")";
    }
    const torch::Tensor out_f = sh_encode(in.to(torch::kFloat32));
    for (int k = 0; k < 16; ++k) EXPECT_NEAR(out_f[0][k].item<double>(), expected[k], 1e-6);
  }
}

TEST(ShEncoding, TcnnSignsAtAxes) {
  // tcnn's l = 1 terms are (−y, z, −x): the opposite of nerfstudio's torch fallback.
  const torch::Tensor x = sh_encode(torch::tensor({1.f, 0.f, 0.f}).reshape({1, 3}));
  EXPECT_LT(x[0][3].item<float>(), -0.48f);
  EXPECT_NEAR(x[0][1].item<float>(), 0.f, 1e-7);
  const torch::Tensor y = sh_encode(torch::tensor({0.f, 1.f, 0.f}).reshape({1, 3}));
  EXPECT_LT(y[0][1].item<float>(), -0.48f);
  EXPECT_GT(y[0][9].item<float>(), 0.58f);  // Y9 = +0.59·y(−3x² + y²)
  const torch::Tensor z = sh_encode(torch::tensor({0.f, 0.f, 1.f}).reshape({1, 3}));
  EXPECT_GT(z[0][2].item<float>(), 0.48f);
  EXPECT_NEAR(z[0][6].item<float>(), 0.94617470f - 0.31539157f, 1e-6);
  EXPECT_NEAR(z[0][12].item<float>(), 2 * 0.37317633f, 1e-6);
}

TEST(ShEncoding, ConstantsMatchClosedForms) {
  // Y0 = 1/(2√π) and the l = 1, 2, 3 normalisations, evaluated through the op.
  const double pi = std::acos(-1.0);
  const torch::Tensor e =
      sh_encode(torch::tensor({1.0, 0.0, 0.0, 0.0, 0.0, 1.0}, torch::kFloat64).reshape({2, 3}));
  EXPECT_NEAR(e[0][0].item<double>(), 1 / (2 * std::sqrt(pi)), 1e-15);
  EXPECT_NEAR(e[0][3].item<double>(), -std::sqrt(3.0) / (2 * std::sqrt(pi)), 1e-15);
  EXPECT_NEAR(e[0][8].item<double>(), std::sqrt(15.0) / (4 * std::sqrt(pi)), 1e-15);
  EXPECT_NEAR(e[0][13].item<double>(), std::sqrt(42.0) / (8 * std::sqrt(pi)), 1e-15);
  EXPECT_NEAR(e[0][15].item<double>(), -std::sqrt(70.0) / (8 * std::sqrt(pi)), 1e-15);
  EXPECT_NEAR(e[1][6].item<double>(), 2 * std::sqrt(5.0) / (4 * std::sqrt(pi)), 1e-15);
  EXPECT_NEAR(e[1][12].item<double>(), 2 * std::sqrt(7.0) / (4 * std::sqrt(pi)), 1e-15);
}

torch::Tensor random_dirs(int64_t n, uint64_t seed, torch::Dtype dtype) {
  torch::manual_seed(seed);
  const torch::Tensor d = torch::randn({n, 3}, torch::kFloat64);
  return (d / d.norm(2, 1, true)).to(dtype).contiguous();
}

TEST(ShEncoding, OpMatchesReferenceValuesAndGradients) {
  for (auto dtype : {torch::kFloat32, torch::kFloat64}) {
    const double tol = dtype == torch::kFloat32 ? 2e-6 : 1e-14;
    for (int degree = 1; degree <= 4; ++degree) {
      const int64_t n = 5000;
      const torch::Tensor dirs = random_dirs(n, 20 + degree, dtype);
      const torch::Tensor up = torch::randn({n, degree * degree}, dtype);
      torch::Tensor a = dirs.clone().set_requires_grad(true);
      torch::Tensor b = dirs.clone().set_requires_grad(true);
      const torch::Tensor ya = sh_encode(a, degree);
      const torch::Tensor yb = sh_encode_reference(b, degree);
      ASSERT_EQ(ya.sizes(), (torch::IntArrayRef{n, degree * degree}));
      EXPECT_LT((ya - yb).abs().max().item<double>(), tol) << "degree " << degree;
      if (degree == 1) continue;  // Y0 is constant: the reference has no graph to differentiate
      (ya * up).sum().backward();
      (yb * up).sum().backward();
      EXPECT_LT((a.grad() - b.grad()).abs().max().item<double>(), 10 * tol) << "degree " << degree;
    }
  }
}

TEST(ShEncoding, FiniteDifferences) {
  const int64_t n = 20;
  const torch::Tensor dirs = random_dirs(n, 30, torch::kFloat64);
  const torch::Tensor w = torch::randn({n, 16}, torch::kFloat64);
  torch::Tensor d = dirs.clone().set_requires_grad(true);
  (sh_encode(d) * w).sum().backward();
  const double eps = 1e-6;
  for (int64_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      torch::Tensor p = dirs.clone(), m = dirs.clone();
      p[i][k] += eps;
      m[i][k] -= eps;
      const double fd = ((sh_encode(p) - sh_encode(m)) * w).sum().item<double>() / (2 * eps);
      EXPECT_NEAR(d.grad()[i][k].item<double>(), fd, 1e-7);
    }
  }
}

TEST(ShEncoding, DegreePrefixes) {
  const torch::Tensor dirs = random_dirs(100, 40, torch::kFloat32);
  const torch::Tensor full = sh_encode(dirs, 4);
  for (int degree = 1; degree <= 3; ++degree) {
    EXPECT_TRUE(torch::equal(sh_encode(dirs, degree), full.narrow(1, 0, degree * degree)));
  }
}

TEST(ShEncoding, TcnnInputMapping) {
  // nerfstudio feeds tcnn (d + 1)/2; tcnn evaluates on 2v − 1: the net effect is SH of d.
  const torch::Tensor dirs = random_dirs(50, 41, torch::kFloat64);
  EXPECT_LT((sh_encode_tcnn_input((dirs + 1) / 2) - sh_encode(dirs)).abs().max().item<double>(),
            1e-15);
  // NeRAF orientation θ = 90°: stored ((cos θ + 1)/2, 0.5, (sin θ + 1)/2) = (0.5, 0.5, 1) → +z.
  const torch::Tensor v = torch::tensor({0.5, 0.5, 1.0}, torch::kFloat64).reshape({1, 3});
  const torch::Tensor z = torch::tensor({0.0, 0.0, 1.0}, torch::kFloat64).reshape({1, 3});
  EXPECT_TRUE(torch::allclose(sh_encode_tcnn_input(v), sh_encode(z)));
}

TEST(ShEncoding, OrthonormalByMonteCarlo) {
  // ∫ Y_i Y_j dΩ = δ_ij, estimated as 4π · mean over uniform directions.
  const int64_t n = 400000;
  const torch::Tensor y = sh_encode(random_dirs(n, 42, torch::kFloat64));
  const torch::Tensor gram = torch::mm(y.t(), y) * (4 * std::acos(-1.0) / n);
  EXPECT_LT((gram - torch::eye(16, torch::kFloat64)).abs().max().item<double>(), 0.02);
}

TEST(ShEncoding, RejectsBadInputs) {
  EXPECT_THROW(sh_encode(torch::rand({4, 2})), c10::Error);
  EXPECT_THROW(sh_encode(torch::rand({4, 3}), 5), c10::Error);
  EXPECT_THROW(sh_encode(torch::rand({4, 3}), 0), c10::Error);
  EXPECT_THROW(sh_encode(torch::rand({4, 3}).to(torch::kInt64)), c10::Error);
}

}  // namespace
}  // namespace neraf::nerf
