#include "neraf/render/loudness.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "neraf/infer/audio_run.h"
#include "neraf/util/error.h"

namespace neraf::render {
namespace {

namespace fs = std::filesystem;

data::Aabb test_aabb() {
  // Train mics x ∈ [0, 2], y = 1.5, z ∈ [0.5, 1.5], plus NeRAF's 1 m.
  return {{-1.0, 0.5, -0.5}, {3.0, 2.5, 2.5}};
}

TEST(FloorGrid, CoversMicBoxPlusMarginInsideAabb) {
  FloorGridOptions o;
  o.spacing_m = 0.5;
  const FloorGrid g = make_floor_grid(test_aabb(), o);
  ASSERT_EQ(g.x.size(), 7u);  // −0.5, 0, ..., 2.5
  ASSERT_EQ(g.z.size(), 5u);  // 0, 0.5, ..., 2
  EXPECT_NEAR(g.x.front(), -0.5, 1e-12);
  EXPECT_NEAR(g.x.back(), 2.5, 1e-12);
  EXPECT_NEAR(g.z.front(), 0.0, 1e-12);
  EXPECT_NEAR(g.z.back(), 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(g.height, 1.5);  // middle of the aabb = the mics' height
  EXPECT_DOUBLE_EQ(g.spacing, 0.5);
  const torch::Tensor p = g.positions();
  ASSERT_EQ(p.sizes(), (std::vector<int64_t>{35, 3}));
  // Row-major over (z, x): entry 8 is (x[1], h, z[1]).
  EXPECT_DOUBLE_EQ(p[8][0].item<double>(), g.x[1]);
  EXPECT_DOUBLE_EQ(p[8][1].item<double>(), 1.5);
  EXPECT_DOUBLE_EQ(p[8][2].item<double>(), g.z[1]);
  const data::Aabb box = test_aabb();
  for (int64_t i = 0; i < p.size(0); ++i) {
    EXPECT_TRUE(inside_open_box(
        {p[i][0].item<double>(), p[i][1].item<double>(), p[i][2].item<double>()}, box));
  }
}

TEST(FloorGrid, DefaultSpacingIsReference) {
  const FloorGrid g = make_floor_grid(test_aabb());
  EXPECT_EQ(g.x.size(), 31u);  // 3 m at 0.1 m, both ends
  EXPECT_EQ(g.z.size(), 21u);
}

TEST(FloorGrid, CoarsensWhenTooManyPoints) {
  FloorGridOptions o;
  o.spacing_m = 0.01;
  o.max_points = 500;
  const FloorGrid g = make_floor_grid(test_aabb(), o);
  EXPECT_LE(g.size(), 500);
  EXPECT_GT(g.spacing, 0.01);
  EXPECT_GT(g.size(), 100);  // not absurdly coarse
}

TEST(FloorGrid, ExplicitHeightAndErrors) {
  FloorGridOptions o;
  o.height_m = 1.0;
  EXPECT_DOUBLE_EQ(make_floor_grid(test_aabb(), o).height, 1.0);
  o.height_m = 2.6;
  EXPECT_THROW(make_floor_grid(test_aabb(), o), Error);
  o.height_m = std::numeric_limits<double>::quiet_NaN();
  o.spacing_m = 0;
  EXPECT_THROW(make_floor_grid(test_aabb(), o), Error);
}

TEST(Loudness, RmsMatchesLibrosaFormulaByHand) {
  // F = 3 (n_fft 4), T = 2. Channel 0 magnitudes: frame 0 [1, 2, 3], frame 1 [0, 0, 4].
  // librosa rms: sqrt(2·Σ w·|S|² / n_fft²), w = (0.5, 1, 0.5):
  //   frame 0: 2·(0.5·1 + 4 + 0.5·9)/16 = 1.125 → 1.0606602; frame 1: 2·(0.5·16)/16 = 1 → 1.
  //   log(1.0606602 + 1) = 0.7230170.
  torch::Tensor mag = torch::tensor({1.0, 0.0, 2.0, 0.0, 3.0, 4.0}, torch::kFloat64).view({3, 2});
  torch::Tensor rms = spectrogram_rms(mag);
  EXPECT_NEAR(rms[0].item<double>(), std::sqrt(1.125), 1e-12);
  EXPECT_NEAR(rms[1].item<double>(), 1.0, 1e-12);

  // Through the log-STFT path: log(mag + 1e-3); channel 1 (huge) must be ignored.
  torch::Tensor log_stft = torch::empty({1, 2, 3, 2}, torch::kFloat32);
  log_stft[0][0] = (mag + 1e-3).log().to(torch::kFloat32);
  log_stft[0][1] = torch::full({3, 2}, 5.0f);
  const torch::Tensor l = log_loudness(log_stft);
  ASSERT_EQ(l.sizes(), (std::vector<int64_t>{1}));
  EXPECT_NEAR(l[0].item<double>(), std::log(std::sqrt(1.125) + 1.0), 1e-5);
}

TEST(Loudness, MagnitudeClipping) {
  // exp(x) − 1e-3 clipped to [0, 1e4]: very negative → 0, very large → 1e4.
  const torch::Tensor m = infer::log_stft_to_magnitude(torch::tensor({-20.0f, 20.0f, 0.0f}));
  EXPECT_FLOAT_EQ(m[0].item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(m[1].item<float>(), 1e4f);
  EXPECT_NEAR(m[2].item<float>(), 0.999f, 1e-6);
}

// A fake field: constant magnitude a = 1/(0.1 + |mic − src|) in every bin and frame, so
// loudness = log(T·a/sqrt(n_fft)) (rms per frame = sqrt(2·a²·(F−1)/n_fft²) = a/sqrt(n_fft)).
constexpr int64_t kF = 5, kT = 4, kC = 2;
torch::Tensor fake_predict(const torch::Tensor& mic, const torch::Tensor& src,
                           const torch::Tensor& yaw) {
  EXPECT_EQ(mic.size(0), src.size(0));
  EXPECT_EQ(mic.size(0), yaw.size(0));
  const torch::Tensor a = 1.0 / (0.1 + (mic - src).norm(2, 1));  // [B]
  return (a + 1e-3).log().to(torch::kFloat32).view({-1, 1, 1, 1}).expand({-1, kC, kF, kT}).clone();
}

TEST(Loudness, MapMatchesClosedFormAndIsBatchInvariant) {
  FloorGridOptions o;
  o.spacing_m = 0.25;
  const FloorGrid g = make_floor_grid(test_aabb(), o);
  const geometry::Vec3 src{1.0, 1.5, 1.0};
  const LoudnessMap a = compute_loudness_map(fake_predict, g, src, 90.0, 7, false);
  const LoudnessMap b = compute_loudness_map(fake_predict, g, src, 90.0, 1000, false);
  ASSERT_EQ(a.values.sizes(), (std::vector<int64_t>{int64_t(g.z.size()), int64_t(g.x.size())}));
  EXPECT_TRUE(torch::allclose(a.values, b.values, 0, 0));
  const double n_fft = 2.0 * (kF - 1);
  for (size_t iz = 0; iz < g.z.size(); iz += 3) {
    for (size_t ix = 0; ix < g.x.size(); ix += 2) {
      const double d = std::hypot(g.x[ix] - src.x, g.z[iz] - src.z);
      const double amp = double(float(std::exp(float(std::log(1.0 / (0.1 + d) + 1e-3))))) - 1e-3;
      EXPECT_NEAR(a.values[iz][ix].item<double>(), std::log(kT * amp / std::sqrt(n_fft)), 1e-4);
    }
  }
  // Loudest at the source's cell.
  const int64_t best = a.values.argmax().item<int64_t>();
  EXPECT_NEAR(g.x[best % g.x.size()], 1.0, 1e-9);
  EXPECT_NEAR(g.z[best / g.x.size()], 1.0, 1e-9);
}

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "neraf_render_test_XXXXXX").string();
    path_ = mkdtemp(tmpl.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string path() const { return path_; }

 private:
  std::string path_;
};

TEST(Loudness, WritesPngAndCsv) {
  TempDir dir;
  FloorGridOptions o;
  o.spacing_m = 0.5;
  const FloorGrid g = make_floor_grid(test_aabb(), o);
  const LoudnessMap map = compute_loudness_map(fake_predict, g, {1.0, 1.5, 1.0}, 0.0, 64, false);
  const std::string png = dir.path() + "/map.png";
  write_loudness_png(png, map);
  write_loudness_csv(csv_path_for(png), map);
  std::ifstream f(png, std::ios::binary);
  char sig[8] = {};
  f.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");
  std::ifstream csv(dir.path() + "/map.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "x_m,y_m,z_m,log_loudness");
  int rows = 0;
  double x = 0, y = 0, z = 0, v = 0;
  char c;
  while (std::getline(csv, line)) {
    if (rows == 0) {
      std::istringstream in(line);
      in >> x >> c >> y >> c >> z >> c >> v;
      EXPECT_DOUBLE_EQ(x, g.x[0]);
      EXPECT_DOUBLE_EQ(z, g.z[0]);
      EXPECT_NEAR(v, map.values[0][0].item<double>(), 1e-5);
    }
    ++rows;
  }
  EXPECT_EQ(rows, g.size());
}

TEST(Loudness, CsvPathFor) {
  EXPECT_EQ(csv_path_for("out/map.png"), "out/map.csv");
  EXPECT_EQ(csv_path_for("map"), "map.csv");
  EXPECT_EQ(csv_path_for("a.dir/map"), "a.dir/map.csv");
  EXPECT_EQ(csv_path_for("out/.hidden"), "out/.hidden.csv");
}

}  // namespace
}  // namespace neraf::render
