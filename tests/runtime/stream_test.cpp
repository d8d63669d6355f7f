// The streaming convolver through the C API (neraf_stream_*), without a model: streamed output
// against direct convolution, the crossfade at RIR changes, a control thread racing the audio
// thread, and every rejected argument.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "neraf/dsp/convolve.h"
#include "neraf/neraf_rt.h"

namespace {

struct StreamFree {
  void operator()(neraf_stream* s) const { neraf_stream_free(s); }
};
using Stream = std::unique_ptr<neraf_stream, StreamFree>;

Stream make_stream(int channels, int block, size_t max_len) {
  neraf_stream* s = nullptr;
  const neraf_status st = neraf_stream_create(nullptr, channels, block, max_len, &s);
  EXPECT_EQ(st, NERAF_OK) << neraf_last_error();
  return Stream(s);
}

std::vector<float> uniform_noise(size_t n, uint32_t seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> x(n);
  for (float& v : x) v = u(gen);
  return x;
}

// Planar [channels, n]: exponentially decaying noise (a plausible RIR), unit energy per channel
// so that outputs of unit-size inputs stay O(1) whatever the length.
std::vector<float> decaying_rir(int channels, size_t n, uint32_t seed) {
  std::vector<float> h = uniform_noise(size_t(channels) * n, seed);
  for (int c = 0; c < channels; ++c) {
    double energy = 0.0;
    for (size_t i = 0; i < n; ++i) {
      float& v = h[size_t(c) * n + i];
      v *= static_cast<float>(std::exp(-3.0 * double(i) / double(n)));
      energy += double(v) * v;
    }
    const float g = static_cast<float>(1.0 / std::sqrt(std::max(energy, 1e-30)));
    for (size_t i = 0; i < n; ++i) h[size_t(c) * n + i] *= g;
  }
  return h;
}

// Low-passed noise (four one-pole sections), peak 1: a smooth input, so that a discontinuity in
// the output stands out against its ordinary sample-to-sample steps.
std::vector<float> smooth_noise(size_t n, uint32_t seed) {
  std::vector<float> x = uniform_noise(n, seed);
  for (int pass = 0; pass < 4; ++pass) {
    float state = 0.0f;
    for (float& v : x) v = state = 0.9f * state + 0.1f * v;
  }
  float peak = 0.0f;
  for (float v : x) peak = std::max(peak, std::abs(v));
  for (float& v : x) v /= peak;
  return x;
}

// The first x.size() samples of x * h, in double.
std::vector<double> direct_convolve(const std::vector<float>& x, const float* h, size_t len) {
  std::vector<double> y(x.size(), 0.0);
  for (size_t n = 0; n < x.size(); ++n) {
    double acc = 0.0;
    const size_t kmax = std::min(len - 1, n);
    for (size_t k = 0; k <= kmax; ++k) acc += double(h[k]) * x[n - k];
    y[n] = acc;
  }
  return y;
}

// Streams x (a multiple of the block size) through s: planar [channels, x.size()].
std::vector<float> stream_all(neraf_stream* s, const std::vector<float>& x, int channels,
                              int block) {
  const size_t n = x.size(), b = size_t(block);
  std::vector<float> out(size_t(channels) * n), buf(size_t(channels) * b);
  for (size_t t = 0; t + b <= n; t += b) {
    EXPECT_EQ(neraf_stream_process(s, x.data() + t, buf.data()), NERAF_OK);
    for (int c = 0; c < channels; ++c)
      std::copy_n(buf.data() + size_t(c) * b, b, out.data() + size_t(c) * n + t);
  }
  return out;
}

float max_jump(const float* y, size_t n) {
  float m = 0.0f;
  for (size_t i = 1; i < n; ++i) m = std::max(m, std::abs(y[i] - y[i - 1]));
  return m;
}

}  // namespace

TEST(Stream, MatchesDirectConvolution) {
  const int channels = 2;
  // Block sizes: the smallest, powers of two, and sizes that are not (FFT of 2B = 2000, 3 * 2^k).
  for (int block : {16, 64, 256, 1000, 1536}) {
    const size_t b = size_t(block);
    // RIR lengths: shorter than a block, exactly one, several, and not multiples.
    for (size_t len : {size_t(1), size_t(5), b - 1, b, b + 1, 3 * b, 3 * b + 7, size_t(2500)}) {
      // max_rir_length exactly the RIR's, then larger (fewer partitions in use than the FDL
      // holds, which also makes the FDL ring wrap at a different place).
      for (size_t max_len : {len, len + 2 * b + 3}) {
        SCOPED_TRACE("block " + std::to_string(block) + ", length " + std::to_string(len) +
                     ", max " + std::to_string(max_len));
        Stream s = make_stream(channels, block, max_len);
        ASSERT_TRUE(s);
        const std::vector<float> h = decaying_rir(channels, len, uint32_t(len + b));
        ASSERT_EQ(neraf_stream_set_rir(s.get(), h.data(), channels, len), NERAF_OK)
            << neraf_last_error();
        ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK) << neraf_last_error();
        // Long enough for the FDL to fill and wrap around a few times.
        const size_t n = ((len + 4 * b) / b + 3) * b;
        const std::vector<float> x = uniform_noise(n, 7);
        const std::vector<float> y = stream_all(s.get(), x, channels, block);
        for (int c = 0; c < channels; ++c) {
          const std::vector<double> ref = direct_convolve(x, h.data() + size_t(c) * len, len);
          double err = 0.0;
          for (size_t i = 0; i < n; ++i)
            err = std::max(err, std::abs(double(y[size_t(c) * n + i]) - ref[i]));
          EXPECT_LE(err, 1e-5) << "channel " << c;
        }
      }
    }
  }
}

// The benchmark's configuration (binaural, 1 s at 48 kHz, 256-sample blocks) against the FFT
// convolution of neraf_dsp.
TEST(Stream, MatchesFftConvolutionOneSecondRir) {
  const int channels = 2, block = 256;
  const size_t len = 48000, n = 256 * 300;
  Stream s = make_stream(channels, block, len);
  ASSERT_TRUE(s);
  const std::vector<float> h = decaying_rir(channels, len, 3);
  ASSERT_EQ(neraf_stream_set_rir(s.get(), h.data(), channels, len), NERAF_OK);
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK) << neraf_last_error();
  const std::vector<float> x = uniform_noise(n, 8);
  const std::vector<float> y = stream_all(s.get(), x, channels, block);
  for (int c = 0; c < channels; ++c) {
    const std::vector<float> hc(h.begin() + long(c * len), h.begin() + long((c + 1) * len));
    const std::vector<float> ref = neraf::dsp::fft_convolve(x, hc);
    double err = 0.0;
    for (size_t i = 0; i < n; ++i)
      err = std::max(err, std::abs(double(y[size_t(c) * n + i]) - double(ref[i])));
    EXPECT_LE(err, 1e-5) << "channel " << c;
  }
}

TEST(Stream, SilentUntilTheFirstRirWhichThenFadesIn) {
  const int block = 64;
  const size_t b = block, len = 100;
  Stream s = make_stream(1, block, len);
  ASSERT_TRUE(s);
  const std::vector<float> x = uniform_noise(8 * b, 9);
  std::vector<float> out(b);
  for (int k = 0; k < 3; ++k) {  // no RIR yet: silence, whatever the input
    ASSERT_EQ(neraf_stream_process(s.get(), x.data() + k * b, out.data()), NERAF_OK);
    for (float v : out) ASSERT_EQ(v, 0.0f);
  }
  const std::vector<float> h = decaying_rir(1, len, 10);
  ASSERT_EQ(neraf_stream_set_rir(s.get(), h.data(), 1, len), NERAF_OK);
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
  const std::vector<double> ref = direct_convolve(x, h.data(), len);
  // Block 3 fades in: the exact convolution (the input history is kept) times a rising weight,
  // from near 0 to exactly 1 at its last sample; block 4 on is the exact convolution.
  ASSERT_EQ(neraf_stream_process(s.get(), x.data() + 3 * b, out.data()), NERAF_OK);
  EXPECT_LT(std::abs(out[0]), 0.01 * std::abs(ref[3 * b]) + 1e-6);
  EXPECT_NEAR(out[b - 1], ref[4 * b - 1], 1e-5);
  for (size_t i = 0; i < b; ++i) EXPECT_LE(std::abs(out[i]), std::abs(ref[3 * b + i]) + 1e-5);
  for (int k = 4; k < 8; ++k) {
    ASSERT_EQ(neraf_stream_process(s.get(), x.data() + k * b, out.data()), NERAF_OK);
    for (size_t i = 0; i < b; ++i) ASSERT_NEAR(out[i], ref[k * b + i], 1e-5);
  }
}

// A RIR change during processing: the block after the change crossfades from the old RIR's output
// to the new one's (both exact over the shared input history), every other block is the exact
// output of the RIR in use, and the largest sample-to-sample jump stays within those of the two
// steady outputs. (Checked by hand: with the crossfade disabled, i.e. switching at the block
// boundary, the jump test fails by a factor of 15 to 20.)
TEST(Stream, RirChangeCrossfadesWithoutAClick) {
  const int channels = 2, block = 256;
  const size_t b = block, len = 3000, n_blocks = 200, n = n_blocks * b;
  const std::vector<float> a = decaying_rir(channels, len, 11);
  const std::vector<float> bb = decaying_rir(channels, len, 12);
  const std::vector<float> x = smooth_noise(n, 13);
  Stream s = make_stream(channels, block, len);
  ASSERT_TRUE(s);
  ASSERT_EQ(neraf_stream_set_rir(s.get(), a.data(), channels, len), NERAF_OK);
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);

  // Change A -> B -> A ... before every 15th block: 13 changes, at varied phases of the input.
  std::vector<float> y(size_t(channels) * n), buf(size_t(channels) * b);
  std::vector<int> rir_of_block(n_blocks);  // 0: A, 1: B
  std::vector<bool> changed(n_blocks, false);
  int current = 0;
  for (size_t k = 0; k < n_blocks; ++k) {
    if (k > 0 && k % 15 == 0) {
      current = 1 - current;
      const std::vector<float>& h = current ? bb : a;
      ASSERT_EQ(neraf_stream_set_rir(s.get(), h.data(), channels, len), NERAF_OK);
      ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
      changed[k] = true;
    }
    rir_of_block[k] = current;
    ASSERT_EQ(neraf_stream_process(s.get(), x.data() + k * b, buf.data()), NERAF_OK);
    for (int c = 0; c < channels; ++c)
      std::copy_n(buf.data() + size_t(c) * b, b, y.data() + size_t(c) * n + k * b);
  }

  for (int c = 0; c < channels; ++c) {
    SCOPED_TRACE("channel " + std::to_string(c));
    const std::vector<double> ya = direct_convolve(x, a.data() + size_t(c) * len, len);
    const std::vector<double> yb = direct_convolve(x, bb.data() + size_t(c) * len, len);
    const float* yc = y.data() + size_t(c) * n;
    double err = 0.0;
    for (size_t k = 0; k < n_blocks; ++k) {
      const std::vector<double>& now = rir_of_block[k] ? yb : ya;
      const std::vector<double>& before = rir_of_block[k] ? ya : yb;
      for (size_t i = 0; i < b; ++i) {
        const size_t t = k * b + i;
        double expected = now[t];
        if (changed[k]) {
          const double w = 0.5 - 0.5 * std::cos(M_PI * double(i + 1) / double(b));
          expected = (1.0 - w) * before[t] + w * now[t];
        }
        err = std::max(err, std::abs(double(yc[t]) - expected));
      }
    }
    EXPECT_LE(err, 1e-5);

    std::vector<float> fa(ya.begin(), ya.end()), fb(yb.begin(), yb.end());
    const float steady = std::max(max_jump(fa.data(), n), max_jump(fb.data(), n));
    float around = 0.0f;  // the largest jump within a block of any change
    for (size_t k = 1; k < n_blocks; ++k)
      if (changed[k]) around = std::max(around, max_jump(yc + (k - 1) * b, 3 * b + 1));
    EXPECT_GT(around, 0.0f);
    EXPECT_LE(around, steady) << "a click at a RIR change";
  }
}

// The audio thread runs process() in a loop while the control thread hands it hundreds of RIRs.
// Each RIR is g * delta (followed by a varying number of zeros, so slots differ in length), with
// channel 1 twice channel 0; the input is constant. Every output block must then be constant g,
// or a monotonic crossfade between two such values, with channel 1 exactly twice channel 0: a
// slot overwritten while it is read would break one of these.
TEST(Stream, ConcurrentRirChangesWhileProcessing) {
  const int channels = 2, block = 64;
  const size_t b = block, max_len = 100 * b;
  Stream s = make_stream(channels, block, max_len);
  ASSERT_TRUE(s);
  std::atomic<bool> stop{false};
  std::atomic<long> blocks{0};
  std::atomic<int> bad{0};
  std::thread audio([&] {
    std::vector<float> in(b, 1.0f), out(channels * b);
    bool started = false;
    while (!stop.load(std::memory_order_relaxed)) {
      if (neraf_stream_process(s.get(), in.data(), out.data()) != NERAF_OK) ++bad;
      const float* o0 = out.data();
      const float* o1 = out.data() + b;
      for (size_t i = 0; i < b; ++i) {
        if (std::abs(o1[i] - 2.0f * o0[i]) > 1e-4f) ++bad;
        // Gains 1 to 4, once the first RIR has faded in (the block it does so ends at its gain).
        if (started && (o0[i] < 1.0f - 1e-4f || o0[i] > 4.0f + 1e-4f)) ++bad;
      }
      started = started || o0[b - 1] != 0.0f;
      // Monotonic within a block (constant, or one crossfade from one gain to another).
      const float sign = o0[b - 1] - o0[0];
      for (size_t i = 1; i < b; ++i)
        if ((o0[i] - o0[i - 1]) * sign < -1e-4f) ++bad;
      ++blocks;
    }
  });

  std::mt19937 gen(14);
  std::uniform_int_distribution<int> gain(1, 4);
  std::uniform_int_distribution<size_t> length(1, max_len);
  std::vector<float> h(channels * max_len);
  for (int i = 0; i < 1000; ++i) {
    const size_t len = length(gen);
    const float g = float(gain(gen));
    std::fill(h.begin(), h.end(), 0.0f);
    h[0] = g;
    h[len] = 2.0f * g;  // channel 1 starts at len (planar [2, len])
    ASSERT_EQ(neraf_stream_set_rir(s.get(), h.data(), channels, len), NERAF_OK);
    if (i % 50 == 0) {
      ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
    }
    if (i % 3 == 0) std::this_thread::yield();
  }
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
  // Let the audio thread pick the last one up.
  const long seen = blocks.load();
  while (blocks.load() < seen + 4) std::this_thread::yield();
  stop = true;
  audio.join();
  EXPECT_EQ(bad.load(), 0);
  EXPECT_GT(blocks.load(), 4);
}

TEST(Stream, RejectsBadArguments) {
  neraf_stream* s = reinterpret_cast<neraf_stream*>(0x1);
  auto expect_invalid = [](neraf_status st, const char* words) {
    EXPECT_EQ(st, NERAF_ERR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(neraf_last_error()).find(words), std::string::npos)
        << "message: " << neraf_last_error();
  };
  expect_invalid(neraf_stream_create(nullptr, 1, 256, 1000, nullptr), "out is NULL");
  for (int block : {0, -256, 15, 16385, 1 << 30}) {
    expect_invalid(neraf_stream_create(nullptr, 1, block, 1000, &s), "[16, 16384]");
    EXPECT_EQ(s, nullptr);
  }
  for (int channels : {0, -1, 17}) expect_invalid(neraf_stream_create(nullptr, channels, 256, 1000, &s), "[1, 16]");
  expect_invalid(neraf_stream_create(nullptr, 2, 256, 0, &s), "max_rir_length is 0");
  expect_invalid(neraf_stream_create(nullptr, 2, 256, size_t(60) * 192000 + 1, &s), "60 s");
  expect_invalid(neraf_stream_create(nullptr, 2, 256, size_t(-1), &s), "60 s");

  Stream good = make_stream(2, 128, 1000);
  ASSERT_TRUE(good);
  std::vector<float> h(2 * 1001, 0.1f), in(128, 0.0f), out(2 * 128);
  expect_invalid(neraf_stream_set_rir(nullptr, h.data(), 2, 10), "stream is NULL");
  expect_invalid(neraf_stream_set_rir(good.get(), nullptr, 2, 10), "rir is NULL");
  expect_invalid(neraf_stream_set_rir(good.get(), h.data(), 1, 10), "channels 1 differs");
  expect_invalid(neraf_stream_set_rir(good.get(), h.data(), 3, 10), "channels 3 differs");
  expect_invalid(neraf_stream_set_rir(good.get(), h.data(), 2, 0), "length is 0");
  expect_invalid(neraf_stream_set_rir(good.get(), h.data(), 2, 1001), "exceeds");
  h[1000 + 7] = NAN;  // channel 1, sample 7 of a 1000-sample RIR
  EXPECT_EQ(neraf_stream_set_rir(good.get(), h.data(), 2, 1000), NERAF_ERR_NOT_FINITE);
  EXPECT_NE(std::string(neraf_last_error()).find("rir[1][7]"), std::string::npos)
      << neraf_last_error();
  h[1000 + 7] = INFINITY;
  EXPECT_EQ(neraf_stream_set_rir(good.get(), h.data(), 2, 1000), NERAF_ERR_NOT_FINITE);

  const neraf_pose pose = {{0, 0, 0}, {1, 1, 1}, 0.0};
  expect_invalid(neraf_stream_set_pose(nullptr, &pose, 0), "stream is NULL");
  expect_invalid(neraf_stream_set_pose(good.get(), nullptr, 0), "pose is NULL");
  expect_invalid(neraf_stream_set_pose(good.get(), &pose, 0), "no model");
  expect_invalid(neraf_stream_wait(nullptr, 10), "stream is NULL");
  expect_invalid(neraf_stream_wait(good.get(), -1), "negative");
  expect_invalid(neraf_stream_process(nullptr, in.data(), out.data()), "stream is NULL");
  expect_invalid(neraf_stream_process(good.get(), nullptr, out.data()), "in is NULL");
  expect_invalid(neraf_stream_process(good.get(), in.data(), nullptr), "out is NULL");
  neraf_stream_free(nullptr);  // a no-op

  // None of the rejected calls changed the stream: no request is pending, output is silence.
  EXPECT_EQ(neraf_stream_wait(good.get(), 0), NERAF_OK);
  ASSERT_EQ(neraf_stream_process(good.get(), in.data(), out.data()), NERAF_OK);
  for (float v : out) EXPECT_EQ(v, 0.0f);
}

// Latest wins: a burst of set_rir calls ends on the last one, and the output is its convolution.
TEST(Stream, LatestRirWins) {
  const int block = 32;
  const size_t b = block, len = 70;
  Stream s = make_stream(1, block, len);
  ASSERT_TRUE(s);
  std::vector<float> h;
  for (uint32_t i = 0; i < 50; ++i) {
    h = decaying_rir(1, len, 100 + i);
    ASSERT_EQ(neraf_stream_set_rir(s.get(), h.data(), 1, len), NERAF_OK);
  }
  ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
  const std::vector<float> x = uniform_noise(10 * b, 15);
  const std::vector<float> y = stream_all(s.get(), x, 1, block);
  const std::vector<double> ref = direct_convolve(x, h.data(), len);
  for (size_t i = 0; i < x.size(); ++i) ASSERT_NEAR(y[i], ref[i], 1e-5) << i;
}

// The output is independent of the stream's heap addresses and of earlier streams: two streams
// fed alike give the same samples bit for bit (plans measured once, then reused by FFTW).
TEST(Stream, TwoStreamsAgreeBitForBit) {
  const int block = 128;
  const size_t len = 1000;
  const std::vector<float> h = decaying_rir(2, len, 16);
  const std::vector<float> x = uniform_noise(20 * block, 17);
  std::vector<float> y[2];
  for (auto& yi : y) {
    Stream s = make_stream(2, block, len);
    ASSERT_TRUE(s);
    ASSERT_EQ(neraf_stream_set_rir(s.get(), h.data(), 2, len), NERAF_OK);
    ASSERT_EQ(neraf_stream_wait(s.get(), 10000), NERAF_OK);
    yi = stream_all(s.get(), x, 2, block);
  }
  EXPECT_EQ(y[0], y[1]);
}
