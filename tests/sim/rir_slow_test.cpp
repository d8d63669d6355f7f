// Heavier physical checks of the RIR simulator (label "slow").
#include <gtest/gtest.h>

#include <cmath>

#include "neraf/sim/rir_simulator.h"
#include "rir_test_util.h"

namespace neraf::sim {
namespace {

using testing::energy;
using testing::shoebox;

// Mean energy per 20 ms window over a set of poses.
std::vector<double> mean_envelope(const RirSimulator& sim, int fs, int windows, int ear = 0) {
  const int win = fs / 50;
  std::vector<double> acc(windows, 0.0);
  const int n_pose = 12;
  for (int p = 0; p < n_pose; ++p) {
    const Source src{{0.7 + 0.3 * p, 1.0 + 0.08 * p, 0.8 + 0.2 * (p % 5)}};
    const Vec3 mic{4.3 - 0.25 * p, 1.6, 3.3 - 0.15 * (p % 7)};
    const auto h = sim.render(src, mic, 30.0 * p);
    for (int w = 0; w < windows; ++w) acc[w] += energy(h[ear], w * win, (w + 1) * win) / n_pose;
  }
  return acc;
}

TEST(RirSimulatorSlow, TailCompensatesForTheImageOrder) {
  // The late tail carries the (expected) energy of the images that are not rendered, so the energy
  // envelope must not depend much on max_order: no hole where the image set ends. Not exactly: the
  // explicit specular images of a shoebox decay slower than Eyring's diffuse estimate (axial
  // paths hit few walls), so high orders carry up to ~2 dB more at 40-140 ms in this room.
  const int fs = 16000, windows = 20;
  std::vector<std::vector<double>> env;
  for (int order : {0, 2, 5, 10}) {
    RirSimOptions o;
    o.binaural = false;
    o.seed = 11;
    Scene s = shoebox({5, 3, 4}, 0.12, 0.15, order, 0.5);
    RirSimulator sim(s, fs, nullptr, o);
    env.push_back(mean_envelope(sim, fs, windows));
  }
  for (size_t k = 0; k + 1 < env.size(); ++k)
    for (int w = 1; w < windows; ++w)  // skip the direct-sound window
      EXPECT_NEAR(10 * std::log10(env[k][w] / env.back()[w]), 0.0, 3.0)
          << "order set " << k << " window " << w;
}

TEST(RirSimulatorSlow, BinauralT60FollowsEyringInSeveralRooms) {
  const Hrtf hrtf(44100);
  struct Room {
    Vec3 size;
    double absorption;
  };
  for (const Room& room : {Room{{5, 3, 4}, 0.08}, Room{{9, 3.5, 7}, 0.2}, Room{{3, 2.5, 3}, 0.3}}) {
    Scene s = shoebox(room.size, room.absorption, 0.1, 10, 2.0);
    RirSimOptions o;
    o.seed = 5;
    RirSimulator sim(s, 44100, &hrtf, o);
    const auto t60 = sim.eyring_t60();
    for (int band : {2, 3, 4}) {
      double mean = 0;
      int n = 0;
      for (int p = 0; p < 3; ++p) {
        const Source src{{room.size.x * (0.2 + 0.2 * p), 1.2, room.size.z * 0.3}};
        const Vec3 mic{room.size.x * (0.8 - 0.15 * p), 1.5, room.size.z * 0.7};
        const auto h = sim.render(src, mic, 90.0 * p);
        for (int ear = 0; ear < 2; ++ear, ++n)
          mean += testing::schroeder_t60(
              testing::octave_bandpass(h[ear], 44100, kOctaveBandsHz[band]), 44100);
      }
      mean /= n;
      EXPECT_NEAR(mean, t60[band], 0.15 * t60[band])
          << "room " << room.size.x << "x" << room.size.y << "x" << room.size.z << " band " << band;
    }
  }
}

TEST(RirSimulatorSlow, FurnishedRoomRirsAreFiniteAndDecay) {
  Scene s = shoebox({5, 3, 4}, 0.1, 0.1, 8, 1.0);
  Material sofa;
  sofa.absorption = {0.2, 0.35, 0.5, 0.6, 0.65, 0.65, 0.6};
  s.materials["sofa"] = sofa;
  s.furniture = {{{1.2, 0.4, 1.0}, {1.8, 0.8, 0.9}, 0, "sofa"},
                 {{3.6, 0.375, 2.5}, {1.2, 0.75, 0.8}, 20, "sofa"}};
  const Hrtf hrtf(48000);
  RirSimulator sim(s, 48000, &hrtf, {});
  for (int i = 0; i < 20; ++i) {
    const Vec3 mic{0.5 + 0.2 * i, 1.5, 3.5};
    const auto h = sim.render(Source{{2.5, 1.2, 2.0}}, mic, 18.0 * i);
    for (const auto& ch : h) {
      for (float v : ch) ASSERT_TRUE(std::isfinite(v));
      EXPECT_LT(energy(ch, 36000), 1e-3 * energy(ch, 0, 12000));
    }
  }
}

}  // namespace
}  // namespace neraf::sim
