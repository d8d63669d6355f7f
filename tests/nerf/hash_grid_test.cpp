// Hash-grid encoding: layout invariants, hand-computed values, the custom op against the LibTorch
// reference (values, table and position gradients), finite differences, determinism across thread
// counts, the module wrapper and input checks.
#include "neraf/nerf/hash_grid.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "neraf/util/error.h"

namespace neraf::nerf {
namespace {

// Restores the LibTorch thread count when a test changes it.
struct ThreadGuard {
  int saved = torch::get_num_threads();
  ~ThreadGuard() { torch::set_num_threads(saved); }
};

// Random points in [0,1]³ plus the 8 cube corners and points with single coordinates at 0 or 1.
torch::Tensor test_points(int64_t n, uint64_t seed, torch::Dtype dtype = torch::kFloat32) {
  torch::manual_seed(seed);
  torch::Tensor x = torch::rand({n, 3}, torch::kFloat64);
  for (int c = 0; c < 8 && c < n; ++c) {
    for (int d = 0; d < 3; ++d) x[c][d] = static_cast<double>((c >> d) & 1);
  }
  for (int64_t i = 8; i < std::min<int64_t>(n, 64); ++i) x[i][i % 3] = static_cast<double>(i & 1);
  return x.to(dtype).contiguous();
}

double max_rel_err(const torch::Tensor& a, const torch::Tensor& b) {
  const double scale = std::max(b.abs().max().item<double>(), 1e-30);
  return (a.to(torch::kFloat64) - b.to(torch::kFloat64)).abs().max().item<double>() / scale;
}

// ---------------------------------------------------------------------------------------------
// Layout

// Independent computation in double precision of the dense levels and the total size.
struct Expected {
  std::vector<int64_t> dense_res;  // resolutions of the dense levels
  int64_t hashed_levels = 0;
  int64_t total = 0;
};

Expected expected_layout(int L, int log2_t, int base, int max_res) {
  Expected e;
  const double growth = std::pow(static_cast<double>(max_res) / base, 1.0 / (L - 1));
  const int64_t t = int64_t{1} << log2_t;
  for (int l = 0; l < L; ++l) {
    const double scale = base * std::pow(growth, l) - 1.0;
    const int64_t res = static_cast<int64_t>(std::ceil(scale - 1e-9)) + 1;
    const int64_t cube = res * res * res;
    if (cube <= t) {
      e.dense_res.push_back(res);
      e.total += (cube + 7) / 8 * 8;
    } else {
      e.hashed_levels += 1;
      e.total += t;
    }
  }
  return e;
}

void expect_layout_matches(const HashGridConfig& cfg) {
  const HashGridLayout layout = HashGridLayout::make(cfg);
  const Expected e = expected_layout(cfg.num_levels, cfg.log2_hashmap_size, cfg.base_resolution,
                                     cfg.max_resolution);
  ASSERT_EQ(layout.num_levels(), cfg.num_levels);
  ASSERT_EQ(layout.offsets.size(), static_cast<size_t>(cfg.num_levels + 1));
  const int n_dense = static_cast<int>(e.dense_res.size());
  for (int l = 0; l < cfg.num_levels; ++l) {
    EXPECT_EQ(layout.offsets[l + 1] - layout.offsets[l], layout.sizes[l]) << "level " << l;
    EXPECT_EQ(layout.sizes[l] % 8, 0) << "level " << l;
    if (l < n_dense) {  // coarse levels are the dense ones
      EXPECT_EQ(layout.dense[l], 1) << "level " << l;
      EXPECT_EQ(layout.resolutions[l], e.dense_res[l]) << "level " << l;
      const int64_t r = e.dense_res[l];
      EXPECT_EQ(layout.sizes[l], (r * r * r + 7) / 8 * 8) << "level " << l;
    } else {
      EXPECT_EQ(layout.dense[l], 0) << "level " << l;
      EXPECT_EQ(layout.sizes[l], int64_t{1} << cfg.log2_hashmap_size) << "level " << l;
    }
  }
  EXPECT_EQ(cfg.num_levels - n_dense, e.hashed_levels);
  EXPECT_EQ(layout.total_entries, e.total);
  EXPECT_EQ(layout.offsets.back(), e.total);
  EXPECT_EQ(layout.num_parameters(), e.total * cfg.features_per_level);
  EXPECT_EQ(layout.output_dim(), cfg.num_levels * cfg.features_per_level);
  EXPECT_FLOAT_EQ(layout.scales[0], static_cast<float>(cfg.base_resolution - 1));
}

TEST(HashGridLayout, NerfactoMainGrid) {
  const HashGridConfig cfg;  // the Nerfacto defaults
  expect_layout_matches(cfg);
  const HashGridLayout layout = HashGridLayout::make(cfg);
  // radiance-field-and-cpu.md §3.3: 5 dense levels of 16, 23, 31, 43, 59 vertices per side,
  // 11 hashed levels of 2^19, 6.10 M entries.
  EXPECT_EQ(layout.resolutions[0], 16);
  EXPECT_EQ(layout.resolutions[4], 59);
  EXPECT_EQ(layout.dense[4], 1);
  EXPECT_EQ(layout.dense[5], 0);
  EXPECT_EQ(layout.total_entries, 6098120);
  EXPECT_NEAR(layout.per_level_scale, std::pow(2.0, 7.0 / 15.0), 1e-6);
}

TEST(HashGridLayout, ProposalGrids) {
  HashGridConfig p1{5, 2, 17, 16, 128};
  HashGridConfig p2{5, 2, 17, 16, 256};
  expect_layout_matches(p1);
  expect_layout_matches(p2);
  // Table bytes as in radiance-field-and-cpu.md §3.3 (3.1 MB and 3.4 MB).
  EXPECT_EQ(HashGridLayout::make(p1).total_entries, 383264);
  EXPECT_EQ(HashGridLayout::make(p2).total_entries, 430080);
  EXPECT_EQ(HashGridLayout::make(p1).dense[2], 1);
  EXPECT_EQ(HashGridLayout::make(p1).dense[3], 0);
  EXPECT_EQ(HashGridLayout::make(p2).dense[1], 1);
  EXPECT_EQ(HashGridLayout::make(p2).dense[2], 0);
}

TEST(HashGridLayout, InvalidConfigsThrowNamedErrors) {
  HashGridConfig c;
  c.features_per_level = 3;
  EXPECT_THROW(HashGridLayout::make(c), neraf::Error);
  c = {};
  c.num_levels = 0;
  EXPECT_THROW(HashGridLayout::make(c), neraf::Error);
  c = {};
  c.max_resolution = 8;  // below base_resolution
  EXPECT_THROW(HashGridLayout::make(c), neraf::Error);
  c = {};
  c.log2_hashmap_size = 40;
  try {
    HashGridLayout::make(c);
    FAIL() << "expected an error";
  } catch (const neraf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("log2_hashmap_size"), std::string::npos);
  }
}

// ---------------------------------------------------------------------------------------------
// Hand-computed values

TEST(HashGridEncode, DenseLevelByHand) {
  // One level, base 2: scale 1, res 2, 8 rows, dense. table[i] = i, so a corner contributes its
  // row index x + 2y + 4z.
  const HashGridLayout layout = HashGridLayout::make({1, 1, 10, 2, 2});
  ASSERT_EQ(layout.total_entries, 8);
  ASSERT_EQ(layout.dense[0], 1);
  const torch::Tensor table = torch::arange(8, torch::kFloat32).reshape({8, 1});
  // x = 0.25 → pos 0.75: grid 0, frac 0.75 on every axis → 0.75·1 + 0.75·2 + 0.75·4.
  // x = 1 → pos 1.5: grid 1, the top corner (2) wraps: row (cx + 2cy + 4cz) mod 8, weights 1/8.
  const torch::Tensor x = torch::tensor({0.25f, 0.25f, 0.25f, 1.f, 1.f, 1.f}).reshape({2, 3});
  const torch::Tensor out = hash_grid_encode(x, table, layout);
  double wrapped = 0;
  for (int c = 0; c < 8; ++c) {
    const int cx = 1 + (c & 1), cy = 1 + ((c >> 1) & 1), cz = 1 + (c >> 2);
    wrapped += 0.125 * ((cx + 2 * cy + 4 * cz) % 8);
  }
  EXPECT_FLOAT_EQ(out[0][0].item<float>(), 5.25f);
  EXPECT_FLOAT_EQ(out[1][0].item<float>(), static_cast<float>(wrapped));
}

TEST(HashGridEncode, HashedLevelByHand) {
  // One level, base 16 (scale 15), T = 16 < 16³ → hashed. x = (1, 2, 3)/16 gives pos = 15x + 0.5
  // = (1.4375, 2.375, 3.3125) exactly: grid (1, 2, 3). The corner rows
  // (x ⊕ 2654435761·y ⊕ 805459861·z) mod 16 were computed by hand (Python, arbitrary precision).
  const HashGridLayout layout = HashGridLayout::make({1, 1, 4, 16, 16});
  ASSERT_EQ(layout.dense[0], 0);
  ASSERT_EQ(layout.total_entries, 16);
  const int rows[8] = {12, 15, 13, 14, 7, 4, 6, 5};
  const double frac[3] = {0.4375, 0.375, 0.3125};
  double expected = 0;
  for (int c = 0; c < 8; ++c) {
    double w = 1;
    for (int d = 0; d < 3; ++d) w *= ((c >> d) & 1) ? frac[d] : 1 - frac[d];
    expected += w * rows[c];
  }
  const torch::Tensor table = torch::arange(16, torch::kFloat32).reshape({16, 1});
  const torch::Tensor x = torch::tensor({1.f / 16, 2.f / 16, 3.f / 16}).reshape({1, 3});
  EXPECT_NEAR(hash_grid_encode(x, table, layout).item<double>(), expected, 1e-5);
  EXPECT_NEAR(hash_grid_encode_reference(x, table, layout).item<double>(), expected, 1e-5);
}

// ---------------------------------------------------------------------------------------------
// Custom op vs the LibTorch reference

struct OpResult {
  torch::Tensor out, grad_table, grad_x;
};

OpResult run(bool reference, const torch::Tensor& x_in, const torch::Tensor& table_in,
             const torch::Tensor& upstream, const HashGridLayout& layout, bool want_grad_x) {
  torch::Tensor x = x_in.detach().clone().set_requires_grad(want_grad_x);
  torch::Tensor table = table_in.detach().clone().set_requires_grad(true);
  torch::Tensor out =
      reference ? hash_grid_encode_reference(x, table, layout) : hash_grid_encode(x, table, layout);
  (out * upstream).sum().backward();
  return {out.detach(), table.grad(), want_grad_x ? x.grad() : torch::Tensor()};
}

void compare_with_reference(const HashGridConfig& cfg, int64_t n, uint64_t seed) {
  const HashGridLayout layout = HashGridLayout::make(cfg);
  const torch::Tensor x = test_points(n, seed);
  torch::manual_seed(seed + 1);
  const torch::Tensor table = torch::randn({layout.total_entries, layout.features()});
  const torch::Tensor upstream = torch::randn({n, layout.output_dim()});
  const OpResult op = run(false, x, table, upstream, layout, true);
  const OpResult ref = run(true, x, table, upstream, layout, true);
  ASSERT_EQ(op.out.sizes(), ref.out.sizes());
  ASSERT_TRUE(op.grad_table.defined());
  ASSERT_TRUE(op.grad_x.defined());
  const double e_out = max_rel_err(op.out, ref.out);
  const double e_table = max_rel_err(op.grad_table, ref.grad_table);
  const double e_x = max_rel_err(op.grad_x, ref.grad_x);
  std::printf("  max |op - ref| / max |ref|: out %.2e, grad table %.2e, grad x %.2e\n", e_out,
              e_table, e_x);
  EXPECT_LT(e_out, 2e-6);
  EXPECT_LT(e_table, 2e-6);
  EXPECT_LT(e_x, 2e-5);
  // Every level must actually be exercised: no all-zero output columns.
  EXPECT_GT(op.out.abs().sum(0).min().item<float>(), 0.f);
}

TEST(HashGridEncode, MatchesReferenceNerfacto) { compare_with_reference({}, 3000, 1); }

TEST(HashGridEncode, MatchesReferenceProposal) {
  compare_with_reference({5, 2, 17, 16, 128}, 4000, 2);
  compare_with_reference({5, 2, 17, 16, 256}, 4000, 3);
}

TEST(HashGridEncode, MatchesReferenceOtherFeatureCounts) {
  compare_with_reference({4, 1, 10, 4, 64}, 2000, 4);
  compare_with_reference({3, 4, 9, 8, 40}, 2000, 5);
  compare_with_reference({2, 8, 8, 3, 30}, 2000, 6);
}

TEST(HashGridEncode, MatchesReferenceInDouble) {
  const HashGridLayout layout = HashGridLayout::make({6, 2, 12, 8, 200});
  const int64_t n = 2000;
  const torch::Tensor x = test_points(n, 7, torch::kFloat64);
  torch::manual_seed(8);
  const torch::Tensor table = torch::randn({layout.total_entries, 2}, torch::kFloat64);
  const torch::Tensor upstream = torch::randn({n, layout.output_dim()}, torch::kFloat64);
  const OpResult op = run(false, x, table, upstream, layout, true);
  const OpResult ref = run(true, x, table, upstream, layout, true);
  EXPECT_LT(max_rel_err(op.out, ref.out), 1e-13);
  EXPECT_LT(max_rel_err(op.grad_table, ref.grad_table), 1e-13);
  EXPECT_LT(max_rel_err(op.grad_x, ref.grad_x), 1e-12);
}

TEST(HashGridEncode, NoPositionGradientUnlessRequested) {
  const HashGridLayout layout = HashGridLayout::make({4, 2, 10, 4, 32});
  const torch::Tensor x = test_points(100, 9);
  const torch::Tensor table = torch::randn({layout.total_entries, 2});
  const OpResult op = run(false, x, table, torch::ones({100, 8}), layout, false);
  EXPECT_FALSE(op.grad_x.defined());
  // The table gradient of a sum of outputs is the total interpolation weight per row: Σ = N·L.
  EXPECT_NEAR(op.grad_table.sum().item<double>(), 100.0 * 4 * 2, 1e-3);
}

TEST(HashGridEncode, OutOfRangeInputsFollowTcnnWrapAround) {
  // Not used by Nerfacto (contracted inputs lie in [0,1]), but the semantics must not depend on
  // the code path: uint32 wrap-around, then modulo the level size.
  const HashGridLayout layout = HashGridLayout::make({6, 2, 12, 8, 200});
  torch::manual_seed(14);
  const int64_t n = 1000;
  const torch::Tensor x = (torch::rand({n, 3}) * 5 - 2).contiguous();
  const torch::Tensor table = torch::randn({layout.total_entries, 2});
  const torch::Tensor upstream = torch::randn({n, layout.output_dim()});
  const OpResult op = run(false, x, table, upstream, layout, true);
  const OpResult ref = run(true, x, table, upstream, layout, true);
  EXPECT_LT(max_rel_err(op.out, ref.out), 2e-6);
  EXPECT_LT(max_rel_err(op.grad_table, ref.grad_table), 2e-6);
  EXPECT_LT(max_rel_err(op.grad_x, ref.grad_x), 2e-5);
}

// ---------------------------------------------------------------------------------------------
// The raw kernels: the AVX-512 path against the portable scalar path

void expect_paths_identical(const HashGridConfig& cfg, const torch::Tensor& x, int threads) {
  const HashGridLayout layout = HashGridLayout::make(cfg);
  const int64_t n = x.size(0);
  torch::manual_seed(15);
  const torch::Tensor table = torch::randn({layout.total_entries, layout.features()});
  const torch::Tensor upstream = torch::randn({n, layout.output_dim()});
  torch::Tensor out[2], grad_table[2], grad_x[2];
  const HashGridPath paths[2] = {HashGridPath::kBest, HashGridPath::kScalar};
  for (int p = 0; p < 2; ++p) {
    out[p] = torch::empty({n, layout.output_dim()});
    grad_table[p] = torch::full_like(table, p == 0 ? 7.f : -3.f);  // must be overwritten
    grad_x[p] = torch::empty({n, 3});
    hash_grid_forward_cpu<float>(x.data_ptr<float>(), n, table.data_ptr<float>(), layout,
                                 out[p].data_ptr<float>(), threads, paths[p]);
    hash_grid_backward_cpu<float>(
        x.data_ptr<float>(), n, table.data_ptr<float>(), upstream.data_ptr<float>(), layout,
        grad_table[p].data_ptr<float>(), grad_x[p].data_ptr<float>(), threads, paths[p]);
  }
  EXPECT_TRUE(torch::equal(out[0], out[1]));
  EXPECT_TRUE(torch::equal(grad_table[0], grad_table[1]));
  EXPECT_TRUE(torch::equal(grad_x[0], grad_x[1]));
}

TEST(HashGridKernel, SimdAndScalarPathsAreBitIdentical) {
  if (!hash_grid_has_simd()) GTEST_SKIP() << "this build has no AVX-512 path";
  // 10007 points: not a multiple of the 16-point blocks, so the scalar tails run too.
  expect_paths_identical({}, test_points(10007, 16), 2);
  expect_paths_identical({5, 2, 17, 16, 256}, test_points(10007, 17), 1);
  // Inputs far outside [0,1] take the per-block scalar fallback of the dense levels.
  torch::manual_seed(18);
  expect_paths_identical({6, 2, 12, 8, 200}, (torch::rand({5003, 3}) * 40 - 20).contiguous(), 2);
}

// ---------------------------------------------------------------------------------------------
// Finite differences (double precision, tiny grid with dense and hashed levels)

TEST(HashGridEncode, FiniteDifferences) {
  // scales 1, 3, 7 → res 2, 4, 8 → sizes 8, 64, min(512, 64): the last level is hashed.
  const HashGridLayout layout = HashGridLayout::make({3, 2, 6, 2, 8});
  ASSERT_EQ(layout.dense[1], 1);
  ASSERT_EQ(layout.dense[2], 0);
  const int64_t n = 12;
  torch::manual_seed(10);
  torch::Tensor x = torch::rand({n, 3}, torch::kFloat64);
  // Keep every coordinate away from cell boundaries at every level so the function is smooth.
  x = (x * 0.8 + 0.1).contiguous();
  const torch::Tensor table = torch::randn({layout.total_entries, 2}, torch::kFloat64);
  const torch::Tensor w = torch::randn({n, layout.output_dim()}, torch::kFloat64);
  auto loss = [&](const torch::Tensor& xx, const torch::Tensor& tt) {
    return (hash_grid_encode(xx, tt, layout) * w).sum().item<double>();
  };
  const OpResult op = run(false, x, table, w, layout, true);

  const double eps = 1e-6;
  for (int64_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      torch::Tensor xp = x.clone(), xm = x.clone();
      xp[i][d] += eps;
      xm[i][d] -= eps;
      const double fd = (loss(xp, table) - loss(xm, table)) / (2 * eps);
      EXPECT_NEAR(op.grad_x[i][d].item<double>(), fd, 1e-6 * std::max(1.0, std::abs(fd)))
          << "x[" << i << "][" << d << "]";
    }
  }
  for (int64_t r = 0; r < layout.total_entries; ++r) {
    for (int f = 0; f < 2; ++f) {
      torch::Tensor tp = table.clone(), tm = table.clone();
      tp[r][f] += eps;
      tm[r][f] -= eps;
      const double fd = (loss(x, tp) - loss(x, tm)) / (2 * eps);
      EXPECT_NEAR(op.grad_table[r][f].item<double>(), fd, 1e-7) << "row " << r;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Determinism

TEST(HashGridEncode, BitIdenticalAcrossThreadCounts) {
  ThreadGuard guard;
  const HashGridLayout layout = HashGridLayout::make({});
  const int64_t n = 40000;
  const torch::Tensor x = test_points(n, 11);
  torch::manual_seed(12);
  const torch::Tensor table = torch::randn({layout.total_entries, 2});
  const torch::Tensor upstream = torch::randn({n, layout.output_dim()});
  std::vector<OpResult> results;
  for (int threads : {1, 2, 3}) {
    torch::set_num_threads(threads);
    results.push_back(run(false, x, table, upstream, layout, true));
  }
  for (size_t k = 1; k < results.size(); ++k) {
    EXPECT_TRUE(torch::equal(results[0].out, results[k].out)) << "threads run " << k;
    EXPECT_TRUE(torch::equal(results[0].grad_table, results[k].grad_table)) << "run " << k;
    EXPECT_TRUE(torch::equal(results[0].grad_x, results[k].grad_x)) << "run " << k;
  }
}

// ---------------------------------------------------------------------------------------------
// Module and input checks

TEST(HashGridModule, SeededInitialisationAndForward) {
  HashGrid grid(HashGridConfig{}, 1337);
  EXPECT_EQ(grid->output_dim(), 32);
  ASSERT_EQ(grid->parameters().size(), 1u);
  EXPECT_EQ(grid->table.sizes(), (torch::IntArrayRef{6098120, 2}));
  EXPECT_LE(grid->table.abs().max().item<float>(), 1e-4f);
  EXPECT_GT(grid->table.std().item<float>(), 5e-5f);  // uniform ±1e-4 has std 5.8e-5
  EXPECT_LT(grid->table.std().item<float>(), 6.5e-5f);
  torch::manual_seed(99);  // the global RNG must not matter
  HashGrid same(HashGridConfig{}, 1337);
  HashGrid other(HashGridConfig{}, 1338);
  EXPECT_TRUE(torch::equal(grid->table, same->table));
  EXPECT_FALSE(torch::equal(grid->table, other->table));

  const torch::Tensor x = test_points(500, 13);
  const torch::Tensor y = grid->forward(x);
  EXPECT_EQ(y.sizes(), (torch::IntArrayRef{500, 32}));
  y.sum().backward();
  ASSERT_TRUE(grid->table.grad().defined());
  EXPECT_NEAR(grid->table.grad().sum().item<double>(), 500.0 * 16 * 2, 1e-2);
}

TEST(HashGridEncode, EmptyInput) {
  const HashGridLayout layout = HashGridLayout::make({4, 2, 10, 4, 32});
  const torch::Tensor table = torch::randn({layout.total_entries, 2}).set_requires_grad(true);
  const torch::Tensor out = hash_grid_encode(torch::zeros({0, 3}), table, layout);
  EXPECT_EQ(out.sizes(), (torch::IntArrayRef{0, 8}));
  out.sum().backward();
  EXPECT_EQ(table.grad().abs().sum().item<float>(), 0.f);
}

TEST(HashGridEncode, RejectsBadInputs) {
  const HashGridLayout layout = HashGridLayout::make({4, 2, 10, 4, 32});
  const torch::Tensor table = torch::randn({layout.total_entries, 2});
  EXPECT_THROW(hash_grid_encode(torch::rand({5, 2}), table, layout), c10::Error);
  EXPECT_THROW(hash_grid_encode(torch::rand({5, 3}, torch::kFloat64), table, layout), c10::Error);
  EXPECT_THROW(hash_grid_encode(torch::rand({3, 5}).t(), table, layout), c10::Error);
  EXPECT_THROW(hash_grid_encode(torch::rand({5, 3}), table.narrow(0, 0, 10), layout), c10::Error);
  EXPECT_THROW(
      hash_grid_encode(torch::rand({5, 3}).to(torch::kInt32), table.to(torch::kInt32), layout),
      c10::Error);
}

}  // namespace
}  // namespace neraf::nerf
