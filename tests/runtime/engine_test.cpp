// The runtime's log-STFT against a slow, straightforward reference written here from the
// definitions (src/neraf/acoustic/nacf.h): the canonical input of every frame built in full, every
// layer as plain loops in double, no folding, no time table, libm's tanh/exp/log.
#include "neraf/runtime/engine.h"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "neraf/neraf_rt.h"
#include "random_model.h"

namespace fs = std::filesystem;
using neraf::rt::ModelData;
using neraf::rt::testing::random_model;
using neraf::rt::testing::RandomModelOptions;

namespace {

// ---- the reference ---------------------------------------------------------------------------

// 2^linspace(0, max, 10) as torch computes it in float32 (part of the definition: the training
// code keeps the float32 frequencies even for float64 encodings).
std::vector<double> frequencies(double max_exp) {
  std::vector<double> f(10);
  const float step = float(max_exp) / 9.0f;
  for (int i = 0; i < 10; ++i) {
    const float e = i < 5 ? step * float(i) : float(max_exp) - step * float(9 - i);
    f[i] = double(std::pow(2.0f, e));
  }
  return f;
}

// NeRFEncoding: [sin(2πx·f) for each dim and f, sin(2πx·f + π/2) likewise, x].
template <typename T>
std::vector<double> nerf_encoding(const std::vector<T>& x, const std::vector<double>& f) {
  std::vector<double> s, out;
  for (T v : x)
    for (double fk : f) s.push_back(double(T(T(v * T(2 * M_PI)) * T(fk))));
  for (double v : s) out.push_back(double(T(std::sin(T(v)))));
  for (double v : s) out.push_back(double(T(std::sin(T(T(v) + T(M_PI / 2))))));
  for (T v : x) out.push_back(double(v));
  return out;
}

std::vector<double> sh4(double x, double y, double z) {
  return {0.28209479177387814,
          -0.48860251190291987 * y,
          0.48860251190291987 * z,
          -0.48860251190291987 * x,
          1.0925484305920792 * x * y,
          -1.0925484305920792 * y * z,
          0.94617469575755997 * z * z - 0.31539156525251999,
          -1.0925484305920792 * x * z,
          0.54627421529603959 * (x * x - y * y),
          0.59004358992664352 * y * (-3 * x * x + y * y),
          2.8906114426405538 * x * y * z,
          0.45704579946446572 * y * (1 - 5 * z * z),
          0.3731763325901154 * z * (5 * z * z - 3),
          0.45704579946446572 * x * (1 - 5 * z * z),
          1.4453057213202769 * z * (x * x - y * y),
          0.59004358992664352 * x * (3 * y * y - x * x)};
}

// bf16_activations: round the inputs of trunk layers 2.. and of the heads to bfloat16 (the bf16
// path's arithmetic).
std::vector<double> reference_log_stft(const ModelData& m, const neraf_pose& pose,
                                       bool bf16_activations = false) {
  auto normalise = [&](const double* p) {
    std::vector<double> q(3);
    for (int k = 0; k < 3; ++k) {
      q[k] = (p[k] - m.box_min[k]) / (m.box_max[k] - m.box_min[k]);
      if (!(q[k] > 0 && q[k] < 1)) return std::vector<double>(3, 0.0);
    }
    return q;
  };
  const std::vector<double> mic = normalise(pose.mic), src = normalise(pose.source);
  const double th = pose.yaw_deg * M_PI / 180.0;
  const std::vector<double> rot = {(std::cos(th) + 1) / 2, 0.5, (std::sin(th) + 1) / 2};
  const std::vector<double> pf = frequencies(m.position_max_freq_exp);
  std::vector<double> pose_in;  // [mic 63, src 63, rot 16, (relative 22)], cast to float below
  for (const auto& p : {mic, src}) {
    const std::vector<double> e = nerf_encoding(p, pf);
    pose_in.insert(pose_in.end(), e.begin(), e.end());
  }
  const std::vector<double> r = sh4(rot[0] * 2 - 1, rot[1] * 2 - 1, rot[2] * 2 - 1);
  pose_in.insert(pose_in.end(), r.begin(), r.end());
  if (m.relative_geometry) {
    double d[3];  // from the metres, not the normalised positions (zero outside the box)
    for (int k = 0; k < 3; ++k) d[k] = pose.source[k] - pose.mic[k];
    const double dist = std::max(std::hypot(d[0], d[1], d[2]), 0.05);
    const double heading = std::atan2(2 * rot[2] - 1, 2 * rot[0] - 1);
    const double azimuth = std::atan2(d[2], d[0]);
    for (int k = 1; k <= 3; ++k) {
      pose_in.push_back(std::cos(k * (azimuth - heading)));
      pose_in.push_back(std::sin(k * (azimuth - heading)));
      pose_in.push_back(std::cos(k * (azimuth + heading)));
      pose_in.push_back(std::sin(k * (azimuth + heading)));
    }
    pose_in.push_back(d[1] / dist);
    pose_in.push_back(std::hypot(d[0], d[2]) / dist);
    const double rel = dist / std::hypot(m.extent_m[0], m.extent_m[1], m.extent_m[2]);
    pose_in.push_back(rel);
    pose_in.push_back(std::log(dist));
    for (int k = 0; k < 3; ++k) {
      pose_in.push_back(std::sin(2 * M_PI * (1 << k) * rel));
      pose_in.push_back(std::cos(2 * M_PI * (1 << k) * rel));
    }
  }
  const int C = m.channels, F = m.n_freq, T = m.max_len;
  std::vector<double> out(size_t(C) * F * T);
  for (int t = 0; t < T; ++t) {
    // The time encoding in float (t/(T − 1) in float, as the training code; T the frames it
    // spans, more than those predicted for a scene of a multi-scene run).
    const int spanned = m.time_frames > 0 ? m.time_frames : T;
    const float x = float(t) / float(spanned - 1);
    std::vector<double> h = nerf_encoding(std::vector<float>{x}, frequencies(8.0));
    for (double v : pose_in) h.push_back(double(float(v)));
    EXPECT_EQ(int64_t(h.size()), m.input_dim());
    for (size_t li = 0; li < m.trunk.size(); ++li) {
      const auto& l = m.trunk[li];
      if (bf16_activations && li > 0)
        for (double& v : h) v = neraf::rt::bf16_to_float(neraf::rt::float_to_bf16(float(v)));
      std::vector<double> y(l.out);
      for (int64_t o = 0; o < l.out; ++o) {
        double acc = l.bias[o];
        for (int64_t i = 0; i < l.in; ++i) acc += double(l.weight[o * l.in + i]) * h[i];
        y[o] = acc > 0 ? acc : acc * m.leaky_slope;
      }
      h = y;
    }
    if (bf16_activations)
      for (double& v : h) v = neraf::rt::bf16_to_float(neraf::rt::float_to_bf16(float(v)));
    for (int c = 0; c < C; ++c)
      for (int f = 0; f < F; ++f) {
        const auto& l = m.heads[c];
        double acc = l.bias[f];
        for (int64_t i = 0; i < l.in; ++i) acc += double(l.weight[f * l.in + i]) * h[i];
        double v = m.output_scale * std::tanh(acc);
        const size_t idx = (size_t(c) * F + f) * T + t;
        if (!m.calibration.empty()) {
          const double mag = std::clamp(std::exp(v) - 1e-3, 0.0, 1e4);
          v = std::log(mag * m.calibration[idx] + 1e-3);
        }
        out[idx] = v;
      }
  }
  return out;
}

// ---- helpers ----------------------------------------------------------------------------------

// Writes the model to a temporary file and loads it through the C API.
class LoadedModel {
 public:
  explicit LoadedModel(const ModelData& m, unsigned flags = 0) {
    std::string t = (fs::temp_directory_path() / "neraf_rt_engine_XXXXXX").string();
    dir_ = ::mkdtemp(t.data());
    path_ = (dir_ / "model.nrf").string();
    neraf::rt::write_model_file(path_, m);
    EXPECT_EQ(neraf_model_load_ex(path_.c_str(), flags, &model_), NERAF_OK) << neraf_last_error();
    neraf_model_get_info(model_, &info_);
  }
  ~LoadedModel() {
    neraf_model_free(model_);
    fs::remove_all(dir_);
  }
  neraf_model* get() const { return model_; }
  const neraf_model_info& info() const { return info_; }
  const std::string& path() const { return path_; }

 private:
  fs::path dir_;
  std::string path_;
  neraf_model* model_ = nullptr;
  neraf_model_info info_{};
};

std::vector<neraf_pose> test_poses() {
  return {
      {{0.5, 1.2, -0.5}, {2.0, 1.5, 1.0}, 0.0},   {{2.9, 0.1, 1.4}, {-0.9, 2.4, -1.9}, 90.0},
      {{1.0, 1.0, 0.0}, {1.01, 1.0, 0.0}, -37.5},  // source 1 cm away: the 5 cm distance clamp
      {{-1.0, 1.0, 0.0}, {0.0, 2.0, 1.0}, 400.0},  // mic on the box's face: normalised to zeros
      {{0.3, 2.2, 0.7}, {0.3, 0.2, 0.7}, 180.0},   // source straight below
  };
}

double max_abs_diff(const std::vector<float>& a, const std::vector<double>& b) {
  EXPECT_EQ(a.size(), b.size());
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, std::fabs(double(a[i]) - b[i]));
  return d;
}

// Max |runtime − reference| over the test poses (the reference of the file's ModelData).
void expect_matches_reference(const RandomModelOptions& o, unsigned flags = NERAF_LOAD_FLOAT32,
                              bool bf16_activations = false, double tolerance = 1e-5) {
  const ModelData written = random_model(o);
  const LoadedModel model(written, flags);
  // A bf16 file holds the rounded weights: the reference uses what the file holds.
  const ModelData m = neraf::rt::read_model_file(model.path());
  neraf_workspace* ws = nullptr;
  ASSERT_EQ(neraf_workspace_create(model.get(), &ws), NERAF_OK);
  std::vector<float> out(size_t(m.channels) * m.n_freq * m.max_len);
  std::vector<neraf_pose> poses = test_poses();
  poses.push_back({{1.0, 1.0, 0.0}, {6.0, 1.5, -3.0}, 45.0});  // source outside (RAF loudspeaker)
  for (const neraf_pose& pose : poses) {
    ASSERT_EQ(
        neraf_query_log_stft(model.get(), ws, &pose, NERAF_ALLOW_OUTSIDE, out.data(), out.size()),
        NERAF_OK)
        << neraf_last_error();
    EXPECT_LT(max_abs_diff(out, reference_log_stft(m, pose, bf16_activations)), tolerance)
        << "pose yaw " << pose.yaw_deg << " relative_geometry " << o.relative_geometry;
  }
  neraf_workspace_free(ws);
}

}  // namespace

TEST(Engine, MatchesTheReference) {
  RandomModelOptions o;
  expect_matches_reference(o);
}

TEST(Engine, MatchesTheReferenceWithRelativeGeometry) {
  RandomModelOptions o;
  o.relative_geometry = true;
  o.position_max_freq_exp = 1.0;  // preset cpu
  o.seed = 2;
  expect_matches_reference(o);
}

// A scene of a multi-scene run at its own length: the first 7 of a 12-frame time encoding.
TEST(Engine, MatchesTheReferenceWithAShorterScene) {
  RandomModelOptions o;
  o.max_len = 7;
  o.time_frames = 12;
  o.seed = 4;
  expect_matches_reference(o);
}

TEST(Engine, MatchesTheReferenceWithoutCalibrationMonoDeeper) {
  RandomModelOptions o;
  o.channels = 1;
  o.calibration = false;
  o.trunk = {40, 8, 32, 24};
  o.seed = 3;
  expect_matches_reference(o);
}

TEST(Engine, MatchesTheReferenceFromBfloat16Storage) {
  RandomModelOptions o;
  o.bf16 = true;
  o.relative_geometry = true;
  o.seed = 4;
  expect_matches_reference(o);
}

// A bf16 model on a CPU with AMX-BF16 or AVX512-BF16: the trunk and heads run in bfloat16, which
// the reference reproduces by rounding the input of each product to bfloat16 (what is left: float32
// summation order, and the rare activation that rounds the other way). Against the float32
// reference, the bf16 error.
TEST(Engine, Bfloat16TrunkAndHeads) {
  RandomModelOptions o;
  o.bf16 = true;
  o.relative_geometry = true;
  o.trunk = {64, 48, 40};  // odd widths: padding of K and N to 32
  o.max_len = 21;          // padding of M to 16
  o.seed = 5;
  {
    const LoadedModel probe(random_model(o), 0);
    if (std::string(neraf_model_compute(probe.get())) == "float32")
      GTEST_SKIP() << "no AMX-BF16 or AVX512-BF16 here: the bf16 trunk runs in float32";
    EXPECT_STREQ(neraf_model_compute(probe.get()),
                 neraf::rt::best_bf16_kernel() == neraf::rt::Bf16Kernel::amx ? "bfloat16-amx"
                                                                             : "bfloat16-avx512");
  }
  expect_matches_reference(o, 0, /*bf16_activations=*/true, 1e-4);   // measured 2.4e-6
  expect_matches_reference(o, 0, /*bf16_activations=*/false, 0.05);  // measured 1.3e-2
}

TEST(Engine, FloatModelsComputeInFloat32) {
  const LoadedModel model(random_model(), 0);
  EXPECT_STREQ(neraf_model_compute(model.get()), "float32");
}

TEST(Engine, OutsideTheBoxEncodesAsTheTrainingCodeDoes) {
  // With NERAF_ALLOW_OUTSIDE a position outside the box is normalised to the zero vector, as
  // data::normalize_position does: any two outside positions give the same result.
  const LoadedModel model(random_model());
  neraf_workspace* ws = nullptr;
  ASSERT_EQ(neraf_workspace_create(model.get(), &ws), NERAF_OK);
  const size_t n = size_t(model.info().channels) * model.info().n_freq * model.info().n_frames;
  std::vector<float> a(n), b(n);
  neraf_pose p1 = {{10.0, 1.0, 0.0}, {2.0, 1.5, 1.0}, 30.0};
  neraf_pose p2 = {{-5.0, -7.0, 9.0}, {2.0, 1.5, 1.0}, 30.0};
  ASSERT_EQ(neraf_query_log_stft(model.get(), ws, &p1, NERAF_ALLOW_OUTSIDE, a.data(), n), NERAF_OK);
  ASSERT_EQ(neraf_query_log_stft(model.get(), ws, &p2, NERAF_ALLOW_OUTSIDE, b.data(), n), NERAF_OK);
  EXPECT_EQ(a, b);
  neraf_workspace_free(ws);
}

// A source outside the box: its position encoding is the zero vector's (the reference's rule),
// its relative geometry the true direction and distance, from the metres.
TEST(Engine, SourceOutsideTheBoxKeepsItsDirectionAndDistance) {
  RandomModelOptions o;
  o.relative_geometry = true;
  const ModelData m = random_model(o);  // box [-1, 3] × [0, 2.5] × [-2, 1.5]
  const neraf::rt::Engine engine(m);
  ASSERT_EQ(engine.pose_dim(), 2 * 63 + 16 + 22);
  const neraf_pose pose = {{1.0, 1.0, 0.0}, {1.0, 1.0, 5.0}, 0.0};  // source 5 m along +z
  std::vector<float> enc(size_t(engine.pose_dim()));
  engine.encode_pose(pose, enc.data());
  for (int i = 0; i < 63; ++i)  // [sin (30), cos (30), raw (3)] of the zero vector
    EXPECT_EQ(enc[63 + i], i >= 30 && i < 60 ? 1.0f : 0.0f) << i;
  const float* g = enc.data() + 2 * 63 + 16;
  // Heading 0, azimuth atan2(dz, dx) = 90°: cos, sin of k·90° for both senses, k = 1..3.
  const float expected_angles[] = {0, 1, 0, 1, -1, 0, -1, 0, 0, -1, 0, -1};
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(g[i], expected_angles[i], 1e-6) << i;
  EXPECT_NEAR(g[12], 0.0, 1e-6);  // level with the listener
  EXPECT_NEAR(g[13], 1.0, 1e-6);
  EXPECT_NEAR(g[14], 5.0 / std::sqrt(34.5), 1e-6);  // 5 m over the box diagonal
  EXPECT_NEAR(g[15], std::log(5.0), 1e-6);
}

TEST(Engine, ConcurrentQueriesEqualSequentialOnes) {
  RandomModelOptions o;
  o.trunk = {96, 64};
  o.max_len = 20;
  const LoadedModel model(random_model(o));
  const neraf_model_info& info = model.info();
  const size_t n_log = size_t(info.channels) * info.n_freq * info.n_frames;
  const size_t n_rir = size_t(info.channels) * info.rir_length;
  const std::vector<neraf_pose> poses = test_poses();
  const unsigned kAny = NERAF_ALLOW_OUTSIDE;  // one test pose lies on the box's face
  // Sequential results, one workspace.
  std::vector<std::vector<float>> log_ref, rir_ref;
  {
    neraf_workspace* ws = nullptr;
    ASSERT_EQ(neraf_workspace_create(model.get(), &ws), NERAF_OK);
    for (const neraf_pose& p : poses) {
      log_ref.emplace_back(n_log);
      rir_ref.emplace_back(n_rir);
      ASSERT_EQ(neraf_query_log_stft(model.get(), ws, &p, kAny, log_ref.back().data(), n_log),
                NERAF_OK);
      ASSERT_EQ(neraf_query_rir(model.get(), ws, &p, kAny, rir_ref.back().data(), n_rir), NERAF_OK);
    }
    neraf_workspace_free(ws);
  }
  // Two threads, each its own workspace, the shared model, many queries in different orders.
  std::vector<int> mismatches(2, 0), failures(2, 0);
  auto worker = [&](int id) {
    neraf_workspace* ws = nullptr;
    if (neraf_workspace_create(model.get(), &ws) != NERAF_OK) {
      ++failures[id];
      return;
    }
    std::vector<float> log(n_log), rir(n_rir);
    for (int round = 0; round < 6; ++round)
      for (size_t k = 0; k < poses.size(); ++k) {
        const size_t i = id == 0 ? k : poses.size() - 1 - k;
        if (neraf_query_log_stft(model.get(), ws, &poses[i], kAny, log.data(), n_log) != NERAF_OK ||
            neraf_query_rir(model.get(), ws, &poses[i], kAny, rir.data(), n_rir) != NERAF_OK)
          ++failures[id];
        if (log != log_ref[i] || rir != rir_ref[i]) ++mismatches[id];
      }
    neraf_workspace_free(ws);
  };
  std::thread a(worker, 0), b(worker, 1);
  a.join();
  b.join();
  EXPECT_EQ(failures, (std::vector<int>{0, 0}));
  EXPECT_EQ(mismatches, (std::vector<int>{0, 0}));
}

// OpenBLAS's thread count (the workspace splits float32 products itself only when BLAS runs
// them on one thread). Test-only: it is process-wide state.
static int set_blas_threads(int n) {
  using Get = int (*)();
  using Set = void (*)(int);
  const auto get = reinterpret_cast<Get>(dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  const auto set = reinterpret_cast<Set>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (!get || !set) return 1;
  const int before = get();
  set(n);
  return before;
}

// One thread or two (columns of the large layers split, channels in parallel): the same numbers
// up to float32 rounding: BLAS may round a block of columns (a float32 trunk layer's half, one
// channel's heads) computed alone differently. The bf16 kernels' split is bit-exact
// (bf16_gemm_test).
static void expect_thread_count_invariant(const RandomModelOptions& o, double tolerance) {
  const LoadedModel model(random_model(o), 0);
  const neraf_model_info& info = model.info();
  const size_t n_log = size_t(info.channels) * info.n_freq * info.n_frames;
  const size_t n_rir = size_t(info.channels) * info.rir_length;
  std::vector<float> log1(n_log), log2(n_log), rir1(n_rir), rir2(n_rir);
  neraf_workspace* ws = nullptr;
  ASSERT_EQ(neraf_workspace_create(model.get(), &ws), NERAF_OK);
  const neraf_pose pose = test_poses()[1];
  const int blas_before = set_blas_threads(1);
  for (int threads : {1, 2}) {
    ASSERT_EQ(neraf_workspace_set_threads(ws, threads), NERAF_OK);
    std::vector<float>& log = threads == 1 ? log1 : log2;
    std::vector<float>& rir = threads == 1 ? rir1 : rir2;
    ASSERT_EQ(neraf_query_log_stft(model.get(), ws, &pose, 0, log.data(), n_log), NERAF_OK);
    ASSERT_EQ(neraf_query_rir(model.get(), ws, &pose, 0, rir.data(), n_rir), NERAF_OK);
  }
  set_blas_threads(blas_before);
  double d_log = 0, d_rir = 0, max_rir = 0;
  for (size_t i = 0; i < n_log; ++i) d_log = std::max(d_log, std::fabs(double(log1[i]) - log2[i]));
  for (size_t i = 0; i < n_rir; ++i) {
    d_rir = std::max(d_rir, std::fabs(double(rir1[i]) - rir2[i]));
    max_rir = std::max(max_rir, std::fabs(double(rir1[i])));
  }
  EXPECT_LE(d_log, tolerance) << neraf_model_compute(model.get());
  EXPECT_LE(d_rir, 10 * tolerance * max_rir) << neraf_model_compute(model.get());
  neraf_workspace_free(ws);
}

TEST(Engine, ResultsDoNotDependOnTheThreadCount) {
  RandomModelOptions o;
  o.trunk = {256, 320, 72};  // 30 frames × 256 × 320 > 2e6 multiply-adds: split in float32
  o.max_len = 30;
  expect_thread_count_invariant(o, 1e-5);  // measured ~1e-6
  o.bf16 = true;  // bf16 where available: 48 × 1024 × 768 > 3e7 splits there
  o.trunk = {1024, 768, 40};
  o.max_len = 48;
  expect_thread_count_invariant(o, 1e-5);  // measured 9.5e-7 with AVX512-BF16
}
