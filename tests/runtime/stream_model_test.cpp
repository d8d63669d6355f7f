// Streams that follow a pose: the worker's neraf_query_rir, handed to the convolver (a small
// random model written with model_file.h, as the C API tests do).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "neraf/neraf_rt.h"
#include "random_model.h"

namespace fs = std::filesystem;

namespace {

struct StreamFree {
  void operator()(neraf_stream* s) const { neraf_stream_free(s); }
};
using Stream = std::unique_ptr<neraf_stream, StreamFree>;

std::vector<float> uniform_noise(size_t n, uint32_t seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> x(n);
  for (float& v : x) v = u(gen);
  return x;
}

class StreamModel : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string t = (fs::temp_directory_path() / "neraf_rt_stream_XXXXXX").string();
    dir_ = ::mkdtemp(t.data());
    const std::string path = (dir_ / "room.nrf").string();
    neraf::rt::write_model_file(path, neraf::rt::testing::random_model());
    ASSERT_EQ(neraf_model_load(path.c_str(), &model_), NERAF_OK) << neraf_last_error();
    ASSERT_EQ(neraf_model_get_info(model_, &info_), NERAF_OK);
    ASSERT_EQ(neraf_workspace_create(model_, &ws_), NERAF_OK);
  }
  void TearDown() override {
    neraf_workspace_free(ws_);
    neraf_model_free(model_);
    fs::remove_all(dir_);
  }
  // The model's RIR at a pose: planar [C, rir_length].
  std::vector<float> rir(const neraf_pose& p) {
    std::vector<float> h(size_t(info_.channels) * size_t(info_.rir_length));
    EXPECT_EQ(neraf_query_rir(model_, ws_, &p, 0, h.data(), h.size()), NERAF_OK)
        << neraf_last_error();
    return h;
  }
  Stream stream(int channels, int block, size_t max_len) {
    neraf_stream* s = nullptr;
    EXPECT_EQ(neraf_stream_create(model_, channels, block, max_len, &s), NERAF_OK)
        << neraf_last_error();
    return Stream(s);
  }

  fs::path dir_;
  neraf_model* model_ = nullptr;
  neraf_workspace* ws_ = nullptr;
  neraf_model_info info_{};
  const neraf_pose a_ = {{0.5, 1.2, -0.5}, {2.0, 1.5, 1.0}, 90.0};
  const neraf_pose b_ = {{2.5, 0.5, 1.0}, {-0.5, 2.0, -1.5}, 200.0};
};

// y[c] = first n samples of x * h[c] (h planar [C, len]), in double.
std::vector<double> convolve(const std::vector<float>& x, const std::vector<float>& h, int c,
                             size_t len) {
  std::vector<double> y(x.size(), 0.0);
  for (size_t n = 0; n < x.size(); ++n)
    for (size_t k = 0; k <= std::min(n, len - 1); ++k)
      y[n] += double(h[size_t(c) * len + k]) * x[n - k];
  return y;
}

}  // namespace

// set_pose + wait, then the stream's output is the convolution with the pose's RIR (the one
// neraf_query_rir gives on another workspace: queries are deterministic).
TEST_F(StreamModel, OutputIsTheConvolutionWithThePosesRir) {
  const int block = 64;
  Stream s = stream(0, block, 0);  // the model's channels and RIR length
  ASSERT_TRUE(s);
  ASSERT_EQ(neraf_stream_set_pose(s.get(), &a_, 0), NERAF_OK) << neraf_last_error();
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK) << neraf_last_error();
  const size_t len = size_t(info_.rir_length), n = 20 * size_t(block);
  const std::vector<float> h = rir(a_);
  const std::vector<float> x = uniform_noise(n, 1);
  std::vector<float> out(size_t(info_.channels) * block);
  std::vector<std::vector<double>> ref;
  for (int c = 0; c < info_.channels; ++c) ref.push_back(convolve(x, h, c, len));
  double err = 0.0, peak = 0.0;
  for (size_t t = 0; t < n; t += size_t(block)) {
    ASSERT_EQ(neraf_stream_process(s.get(), x.data() + t, out.data()), NERAF_OK);
    for (int c = 0; c < info_.channels; ++c)
      for (size_t i = 0; i < size_t(block); ++i) {
        err = std::max(err, std::abs(out[size_t(c) * block + i] - ref[c][t + i]));
        peak = std::max(peak, std::abs(ref[c][t + i]));
      }
  }
  // Float rounding grows with the RIR's size (this random model's RIRs are not normalised).
  EXPECT_LE(err, 1e-5 * peak) << "peak " << peak;
}

// A max_rir_length below the model's truncates its RIRs.
TEST_F(StreamModel, ShorterMaxRirLengthTruncates) {
  const int block = 32;
  const size_t len = size_t(info_.rir_length), cut = len / 3, n = 16 * size_t(block);
  Stream s = stream(info_.channels, block, cut);
  ASSERT_TRUE(s);
  ASSERT_EQ(neraf_stream_set_pose(s.get(), &b_, 0), NERAF_OK);
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
  const std::vector<float> full = rir(b_);
  std::vector<float> h(size_t(info_.channels) * cut);  // [C, cut]
  for (int c = 0; c < info_.channels; ++c)
    std::copy_n(full.begin() + long(size_t(c) * len), cut, h.begin() + long(size_t(c) * cut));
  const std::vector<float> x = uniform_noise(n, 2);
  std::vector<float> out(size_t(info_.channels) * block);
  std::vector<std::vector<double>> ref;
  for (int c = 0; c < info_.channels; ++c) ref.push_back(convolve(x, h, c, cut));
  double err = 0.0, peak = 0.0;
  for (size_t t = 0; t < n; t += size_t(block)) {
    ASSERT_EQ(neraf_stream_process(s.get(), x.data() + t, out.data()), NERAF_OK);
    for (int c = 0; c < info_.channels; ++c)
      for (size_t i = 0; i < size_t(block); ++i) {
        err = std::max(err, std::abs(out[size_t(c) * block + i] - ref[c][t + i]));
        peak = std::max(peak, std::abs(ref[c][t + i]));
      }
  }
  EXPECT_LE(err, 1e-5 * peak) << "peak " << peak;
}

// Poses are checked on the calling thread, with the query's statuses; nothing is posted.
TEST_F(StreamModel, SetPoseValidatesSynchronously) {
  Stream s = stream(0, 64, 0);
  ASSERT_TRUE(s);
  neraf_pose p = a_;
  p.mic[1] = NAN;
  EXPECT_EQ(neraf_stream_set_pose(s.get(), &p, 0), NERAF_ERR_NOT_FINITE);
  p = a_;
  p.yaw_deg = INFINITY;
  EXPECT_EQ(neraf_stream_set_pose(s.get(), &p, 0), NERAF_ERR_NOT_FINITE);
  p = a_;
  p.source[0] = 10.0;  // box x in [-1, 3]
  EXPECT_EQ(neraf_stream_set_pose(s.get(), &p, 0), NERAF_ERR_OUTSIDE);
  EXPECT_NE(std::string(neraf_last_error()).find("source"), std::string::npos);
  EXPECT_EQ(neraf_stream_set_pose(s.get(), &p, NERAF_ALLOW_OUTSIDE), NERAF_OK);
  EXPECT_EQ(neraf_stream_set_pose(s.get(), &a_, 0x80), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
}

TEST_F(StreamModel, CreateChecksAgainstTheModel) {
  neraf_stream* s = nullptr;
  EXPECT_EQ(neraf_stream_create(model_, 1, 64, 0, &s), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(neraf_last_error()).find("differs from the model's 2"), std::string::npos)
      << neraf_last_error();
  EXPECT_EQ(s, nullptr);
  EXPECT_EQ(neraf_stream_create(model_, 0, 8, 0, &s), NERAF_ERR_INVALID_ARGUMENT);
  // With a model, set_rir works as well (same channel count), and latest wins across both.
  Stream good = stream(0, 64, 0);
  ASSERT_TRUE(good);
  std::vector<float> h(size_t(info_.channels) * 10, 0.0f);
  EXPECT_EQ(neraf_stream_set_rir(good.get(), h.data(), 1, 10), NERAF_ERR_INVALID_ARGUMENT);
  ASSERT_EQ(neraf_stream_set_pose(good.get(), &a_, 0), NERAF_OK);
  ASSERT_EQ(neraf_stream_set_rir(good.get(), h.data(), info_.channels, 10), NERAF_OK);
  ASSERT_EQ(neraf_stream_wait(good.get(), 10000), NERAF_OK);
  std::vector<float> in(64, 1.0f), out(size_t(info_.channels) * 64);
  // Whether or not the worker computed the pose's RIR before set_rir came, the zero RIR is the
  // newest published when processing starts: silence from the first block on.
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(neraf_stream_process(good.get(), in.data(), out.data()), NERAF_OK);
    for (float v : out) ASSERT_EQ(v, 0.0f);
  }
}

// A moving listener: the control thread sets hundreds of poses while the audio thread streams;
// the output stays finite, and freeing the stream with a query in flight does not hang.
TEST_F(StreamModel, PosesFromAControlThreadWhileProcessing) {
  const int block = 64;
  Stream s = stream(0, block, 0);
  ASSERT_TRUE(s);
  std::atomic<bool> stop{false};
  std::atomic<int> bad{0};
  std::atomic<long> blocks{0};
  std::thread audio([&] {
    const std::vector<float> x = uniform_noise(size_t(block), 3);
    std::vector<float> out(size_t(info_.channels) * block);
    while (!stop.load(std::memory_order_relaxed)) {
      if (neraf_stream_process(s.get(), x.data(), out.data()) != NERAF_OK) ++bad;
      for (float v : out)
        if (!std::isfinite(v)) ++bad;
      ++blocks;
    }
  });
  for (int i = 0; i < 300; ++i) {
    const double u = double(i) / 300.0;
    const neraf_pose p = {{-0.5 + 3.0 * u, 1.2, -0.5}, {2.0, 1.5, 1.0 - 2.0 * u}, 360.0 * u};
    ASSERT_EQ(neraf_stream_set_pose(s.get(), &p, 0), NERAF_OK) << neraf_last_error();
    if (i % 40 == 0) {
      ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
    }
  }
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
  while (blocks.load() < 10) std::this_thread::yield();
  stop = true;
  audio.join();
  EXPECT_EQ(bad.load(), 0);
  ASSERT_EQ(neraf_stream_set_pose(s.get(), &b_, 0), NERAF_OK);
  s.reset();  // the worker may be mid-query: free waits for it
}
