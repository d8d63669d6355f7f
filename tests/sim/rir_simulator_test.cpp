#include "neraf/sim/rir_simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numeric>

#include "neraf/geometry/box.h"
#include "neraf/util/error.h"
#include "rir_test_util.h"

namespace neraf::sim {
namespace {

using testing::argmax_abs;
using testing::energy;
using testing::onset;
using testing::shoebox;

RirSimOptions mono_dry() {  // direct path and reflections only, exact 1/r, no air
  RirSimOptions o;
  o.binaural = false;
  o.late_tail = false;
  o.air_absorption = false;
  return o;
}

const Hrtf& kemar44() {
  static const Hrtf h(44100);  // read-only after construction; shared to keep the suite fast
  return h;
}

TEST(RirSimulator, ShapeAndChannels) {
  Scene s = shoebox({5, 3, 4}, 0.2, 0.1, 3, 0.5);
  RirSimulator mono(s, 48000, nullptr, mono_dry());
  const auto h = mono.render(Source{{1, 1.5, 1}}, {3, 1.5, 3}, 0);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].size(), 24000u);
  EXPECT_EQ(mono.length_samples(), 24000);
  RirSimulator bin(s, 44100, &kemar44(), {});
  const auto hb = bin.render(Source{{1, 1.5, 1}}, {3, 1.5, 3}, 0);
  ASSERT_EQ(hb.size(), 2u);
  EXPECT_EQ(hb[0].size(), 22050u);
  EXPECT_EQ(hb[1].size(), 22050u);
  for (const auto& ch : hb)
    for (float v : ch) ASSERT_TRUE(std::isfinite(v));
}

TEST(RirSimulator, ImageCountMatchesTheOrderFormula) {
  for (int n : {0, 1, 3, 8}) {
    Scene s = shoebox({5, 3, 4}, 0.2, 0.1, n);
    RirSimulator sim(s, 48000, nullptr, mono_dry());
    const auto arr = sim.arrivals(Source{{1, 1, 1}}, {4, 2, 3});
    EXPECT_EQ(static_cast<int>(arr.size()), (2 * n + 1) * (2 * n * n + 2 * n + 3) / 3)
        << "order " << n;
    for (const Arrival& a : arr) EXPECT_LE(a.order, n);
  }
}

TEST(RirSimulator, FirstOrderReflectionsAreTheMirrorPaths) {
  Scene s = shoebox({5, 3, 4}, 0.3, 0.2, 1);
  RirSimulator sim(s, 48000, nullptr, mono_dry());
  const Vec3 src{1, 1.2, 1.5}, mic{3.5, 1.7, 2.5};
  const auto arr = sim.arrivals(Source{src}, mic);
  ASSERT_EQ(arr.size(), 7u);
  std::vector<double> expected = {geometry::norm(src - mic)};
  for (int a = 0; a < 3; ++a) {
    Vec3 lo = src, hi = src;
    lo[a] = -src[a];
    hi[a] = 2 * s.size[a] - src[a];
    expected.push_back(geometry::norm(lo - mic));
    expected.push_back(geometry::norm(hi - mic));
  }
  std::sort(expected.begin(), expected.end());
  const double refl = std::sqrt((1 - 0.3) * (1 - 0.2));
  for (size_t i = 0; i < arr.size(); ++i) {
    EXPECT_NEAR(arr[i].distance_m, expected[i], 1e-9);
    EXPECT_NEAR(arr[i].delay_s, expected[i] / 343.0, 1e-12);
    const double g = (arr[i].order == 0 ? 1.0 : refl) / expected[i];
    for (double v : arr[i].gain) EXPECT_NEAR(v, g, 1e-12);
  }
}

TEST(RirSimulator, DirectPathArrivesAtDistanceOverSpeedOfSound) {
  Scene s = shoebox({6, 3, 5}, 0.2, 0.1, 0, 0.1);
  for (int fs : {44100, 48000}) {
    RirSimulator sim(s, fs, nullptr, mono_dry());
    for (const Vec3& mic : {Vec3{3.3, 1.2, 2.7}, Vec3{5.1, 2.5, 4.4}, Vec3{1.9, 1.5, 1.13}}) {
      const Vec3 src{1, 1.5, 1};
      const auto h = sim.render(Source{src}, mic, 0);
      const double expected = geometry::norm(src - mic) / 343.0 * fs;
      EXPECT_NEAR(static_cast<double>(argmax_abs(h[0])), expected, 0.5 + 1e-9) << fs;
    }
  }
}

TEST(RirSimulator, BinauralFrontalDirectPathArrivesAtDistanceOverSpeedOfSound) {
  Scene s = shoebox({6, 3, 5}, 0.2, 0.1, 0, 0.1);
  RirSimOptions o;
  o.late_tail = false;
  o.air_absorption = false;
  RirSimulator sim(s, 44100, &kemar44(), o);
  const Vec3 mic{3, 1.5, 4};
  const Vec3 src = mic + Vec3{0, 0, -2.37};  // straight ahead for yaw 0 (forward = −z)
  const auto h = sim.render(Source{src}, mic, 0);
  const double expected = 2.37 / 343.0 * 44100;
  const double mean_onset = 0.5 * (onset(h[0]) + onset(h[1]));
  EXPECT_NEAR(mean_onset, expected, 2.0);
  EXPECT_NEAR(energy(h[0]) / energy(h[1]), 1.0, 0.3);
}

TEST(RirSimulator, AmplitudeFollowsInverseDistance) {
  Scene s = shoebox({8, 3, 8}, 0.2, 0.1, 0, 0.1);
  RirSimulator sim(s, 48000, nullptr, mono_dry());
  const Vec3 src{1, 1.5, 1};
  // The DC sum of the direct-path impulse is its amplitude whatever the fractional delay.
  auto amplitude = [&](double r) {
    const auto h = sim.render(Source{src}, src + Vec3{0.6 * r, 0, 0.8 * r}, 0);
    return std::accumulate(h[0].begin(), h[0].end(), 0.0);
  };
  const double a1 = amplitude(1.0), a2 = amplitude(2.0), a4 = amplitude(4.0);
  EXPECT_NEAR(a1, 1.0, 0.01);
  EXPECT_NEAR(a1 / a2, 2.0, 0.02);
  EXPECT_NEAR(a2 / a4, 2.0, 0.02);
  // Energy too (the band merge is an exact impulse).
  const auto h1 = sim.render(Source{src}, src + Vec3{1, 0, 0}, 0);
  const auto h2 = sim.render(Source{src}, src + Vec3{2, 0, 0}, 0);
  EXPECT_NEAR(energy(h1[0]) / energy(h2[0]), 4.0, 0.2);
}

TEST(RirSimulator, AirAbsorptionDampsHighBandsOverDistance) {
  Scene s = shoebox({20, 3, 20}, 0.2, 0.1, 0, 0.1);
  RirSimOptions o = mono_dry();
  o.air_absorption = true;
  RirSimulator sim(s, 48000, nullptr, o);
  const auto arr = sim.arrivals(Source{{1, 1.5, 1}}, {15, 1.5, 15});
  ASSERT_EQ(arr.size(), 1u);
  const double r = arr[0].distance_m;
  EXPECT_NEAR(arr[0].gain[0] * r, 1.0, 0.01);  // 125 Hz: < 0.001 dB/m
  EXPECT_LT(arr[0].gain[6] * r, 0.9);          // 8 kHz: ~0.1 dB/m over ~20 m
  EXPECT_GT(arr[0].gain[6] * r, 0.5);
  for (int b = 1; b < 7; ++b) EXPECT_LT(arr[0].gain[b], arr[0].gain[b - 1]);
}

TEST(RirSimulator, SourceOnTheLeftReachesTheLeftEarEarlierAndLouder) {
  Scene s = shoebox({6, 3, 6}, 0.3, 0.1, 0, 0.1);
  RirSimOptions o;
  o.late_tail = false;
  RirSimulator sim(s, 44100, &kemar44(), o);
  const Vec3 mic{3, 1.5, 3};
  struct Case {
    double yaw;
    Vec3 offset;
    bool left;
  };
  // forward(θ) = (−sin θ, 0, −cos θ); left ear along forward(θ + 90°).
  for (const Case& c :
       {Case{0, {-2, 0, 0}, true}, Case{0, {2, 0, 0}, false}, Case{90, {0, 0, 2}, true},
        Case{90, {0, 0, -2}, false}, Case{180, {2, 0, 0}, true}, Case{270, {0, 0, -2}, true}}) {
    const auto h = sim.render(Source{mic + c.offset}, mic, c.yaw);
    const size_t ol = onset(h[0]), orr = onset(h[1]);
    const double el = energy(h[0]), er = energy(h[1]);
    if (c.left) {
      EXPECT_LT(ol + 10, orr) << "yaw " << c.yaw;
      EXPECT_GT(el, 3 * er) << "yaw " << c.yaw;
    } else {
      EXPECT_LT(orr + 10, ol) << "yaw " << c.yaw;
      EXPECT_GT(er, 3 * el) << "yaw " << c.yaw;
    }
  }
}

TEST(RirSimulator, CardioidIsQuieterBehindThanInFront) {
  Scene s = shoebox({8, 3, 8}, 0.2, 0.1, 0, 0.1);
  RirSimOptions o = mono_dry();
  o.cardioid_floor = 0.1;
  RirSimulator sim(s, 48000, nullptr, o);
  Source src{{4, 1.5, 4}, -90, "cardioid"};  // forward(−90°) = (+1, 0, 0)
  auto amplitude = [&](const Source& so, Vec3 mic) {
    const auto h = sim.render(so, mic, 0);
    return std::accumulate(h[0].begin(), h[0].end(), 0.0);
  };
  const double front = amplitude(src, {6, 1.5, 4}), back = amplitude(src, {2, 1.5, 4});
  const double side = amplitude(src, {4, 1.5, 6});
  EXPECT_NEAR(front, 0.5, 0.005);        // D = 1 at 2 m
  EXPECT_NEAR(back, 0.1 * 0.5, 0.001);   // the floor behind
  EXPECT_NEAR(side, 0.55 * 0.5, 0.003);  // 0.1 + 0.9·0.5
  src.directivity = "omni";
  EXPECT_NEAR(amplitude(src, {6, 1.5, 4}), amplitude(src, {2, 1.5, 4}), 1e-4);
}

TEST(RirSimulator, CardioidDirectivityUsesTheDepartureDirectionOfReflections) {
  // Source at the room centre facing +x; the x1-wall reflection leaves towards +x (front), the
  // x0-wall reflection towards −x (back), whatever the microphone position.
  Scene s = shoebox({6, 3, 6}, 0.2, 0.0, 1, 0.1);
  RirSimOptions o = mono_dry();
  RirSimulator sim(s, 48000, nullptr, o);
  const Source src{{3, 1.5, 3}, -90, "cardioid"};
  const Vec3 mic{3, 1.5, 4.5};
  for (const Arrival& a : sim.arrivals(src, mic)) {
    if (a.order != 1 || std::abs(a.direction_world.x) < 0.5) continue;
    // direction_world points from the mic to the image: +x → image behind x = 6 (front reflection).
    const double d = a.gain[3] * a.distance_m / std::sqrt(1 - 0.2);
    if (a.direction_world.x > 0) {
      EXPECT_GT(d, 0.8);
    } else {
      EXPECT_LT(d, 0.3);
    }
  }
}

TEST(RirSimulator, EyringT60MatchesTheFormula) {
  Scene s = shoebox({5, 3, 4}, 0.1);
  RirSimOptions o;
  o.binaural = false;
  o.air_absorption = false;
  RirSimulator sim(s, 48000, nullptr, o);
  const double V = 60, S = 2 * (15 + 20 + 12);
  const double expected = 24 * std::log(10.0) * V / (343.0 * -S * std::log(0.9));
  for (double t : sim.eyring_t60()) EXPECT_NEAR(t, expected, 1e-9);
  // Air absorption shortens the high bands only noticeably (500 Hz: 2.7 dB/km, 4mV ≈ 1.5 % of the
  // wall term here).
  o.air_absorption = true;
  RirSimulator air(s, 48000, nullptr, o);
  EXPECT_LT(air.eyring_t60()[2], expected);
  EXPECT_NEAR(air.eyring_t60()[2], expected, 0.025 * expected);
  EXPECT_LT(air.eyring_t60()[6], 0.8 * expected);
  // Furniture on the floor adds its faces' absorption and removes its volume.
  Material sofa;
  sofa.absorption.fill(0.5);
  s.materials["sofa"] = sofa;
  s.furniture.push_back({{2, 0.5, 2}, {1, 1, 1}, 0, "sofa"});
  RirSimulator furnished(s, 48000, nullptr, [] {
    RirSimOptions x;
    x.binaural = false;
    x.air_absorption = false;
    return x;
  }());
  const double S2 = S - 1 + 5, A2 = 0.1 * (S - 1) + 0.5 * 5, V2 = 59;
  const double expected2 = 24 * std::log(10.0) * V2 / (343.0 * -S2 * std::log(1 - A2 / S2));
  EXPECT_NEAR(furnished.eyring_t60()[3], expected2, 1e-9);
}

TEST(RirSimulator, MeasuredT60FollowsEyringInTheMidBands) {
  for (double absorption : {0.1, 0.25}) {
    Scene s = shoebox({5, 3, 4}, absorption, 0.1, 8, 1.5);
    RirSimOptions o;
    o.binaural = false;
    o.seed = 7;
    const int fs = 16000;
    RirSimulator sim(s, fs, nullptr, o);
    const auto t60 = sim.eyring_t60();
    const std::vector<std::pair<Vec3, Vec3>> poses = {{{1, 1.2, 1}, {3.8, 1.6, 2.9}},
                                                      {{4, 2, 3}, {1.5, 1.1, 0.8}}};
    for (int band : {2, 3, 4}) {  // 500 Hz, 1 kHz, 2 kHz
      double mean = 0;
      for (const auto& [src, mic] : poses) {
        const auto h = sim.render(Source{src}, mic, 0);
        mean +=
            testing::schroeder_t60(testing::octave_bandpass(h[0], fs, kOctaveBandsHz[band]), fs) /
            poses.size();
      }
      EXPECT_NEAR(mean, t60[band], 0.15 * t60[band])
          << "absorption " << absorption << " band " << band;
    }
  }
}

TEST(RirSimulator, DeterministicForASeedAndIndependentOfThreads) {
  Scene s = shoebox({5, 3, 4}, 0.2, 0.1, 4, 0.3);
  RirSimOptions o;
  o.seed = 42;
  RirSimulator sim(s, 44100, &kemar44(), o);
  const Source src{{1, 1.5, 1}};
  const std::vector<Vec3> mics = {{3, 1.5, 3}, {4, 1.2, 1}, {2, 2, 3.5}, {0.5, 1, 2}};
  std::vector<std::vector<std::vector<float>>> serial, parallel(mics.size());
  for (const Vec3& m : mics) serial.push_back(sim.render(src, m, 90));
#pragma omp parallel for num_threads(2) schedule(dynamic, 1)
  for (int i = static_cast<int>(mics.size()) - 1; i >= 0; --i)
    parallel[i] = sim.render(src, mics[i], 90);
  for (size_t i = 0; i < mics.size(); ++i) EXPECT_EQ(serial[i], parallel[i]);
  // Another simulator with the same seed gives the same numbers; another seed changes the tail
  // only.
  RirSimulator again(s, 44100, &kemar44(), o);
  EXPECT_EQ(again.render(src, mics[0], 90), serial[0]);
  o.seed = 43;
  RirSimulator other(s, 44100, &kemar44(), o);
  const auto h = other.render(src, mics[0], 90);
  EXPECT_NE(h, serial[0]);
  const size_t direct = static_cast<size_t>(geometry::norm(src.position - mics[0]) / 343.0 * 44100);
  for (size_t i = 0; i + 20 < direct; ++i) EXPECT_EQ(h[0][i], serial[0][0][i]);
  // Different poses get different (decorrelated) tails.
  const auto a = sim.render(src, {3, 1.5, 3}, 90), b = sim.render(src, {3.01, 1.5, 3}, 90);
  const size_t from = 6000;
  double ab = 0;
  for (size_t i = from; i < a[0].size(); ++i) ab += double(a[0][i]) * b[0][i];
  EXPECT_LT(std::abs(ab) / std::sqrt(energy(a[0], from) * energy(b[0], from)), 0.3);
}

TEST(RirSimulator, BinauralTailIsPartlyDecorrelatedBetweenEars) {
  Scene s = shoebox({5, 3, 4}, 0.15, 0.1, 2, 0.6);
  RirSimulator sim(s, 44100, &kemar44(), {});
  const auto h = sim.render(Source{{1, 1.5, 1}}, {3, 1.5, 3}, 0);
  auto corr = [&](double fc) {
    const auto l = testing::octave_bandpass(h[0], 44100, fc),
               r = testing::octave_bandpass(h[1], 44100, fc);
    double lr = 0;
    const size_t from = 8000;
    for (size_t i = from; i < l.size(); ++i) lr += double(l[i]) * r[i];
    return lr / std::sqrt(energy(l, from) * energy(r, from));
  };
  EXPECT_GT(corr(125), 0.7);             // diffuse-field coherence sinc(kd) ≈ 0.97 at 125 Hz
  EXPECT_LT(std::abs(corr(2000)), 0.3);  // ≈ 0 above 1 kHz
}

TEST(RirSimulator, FurnitureBetweenSourceAndMicOccludesTheDirectPath) {
  Scene s = shoebox({6, 3, 6}, 0.2, 0.1, 0, 0.1);
  Material wood;
  wood.absorption.fill(0.1);
  s.materials["wood"] = wood;
  const Vec3 src{1, 1.0, 3}, mic{5, 1.0, 3};
  RirSimulator open(s, 48000, nullptr, mono_dry());
  s.furniture.push_back({{3, 0.75, 3}, {0.8, 1.5, 1.2}, 30, "wood"});  // a cabinet in between
  RirSimOptions o = mono_dry();
  o.furniture_reflections = false;
  RirSimulator blocked(s, 48000, nullptr, o);
  const auto a_open = open.arrivals(Source{src}, mic),
             a_blocked = blocked.arrivals(Source{src}, mic);
  ASSERT_EQ(a_blocked.size(), 1u);
  EXPECT_TRUE(a_blocked[0].occluded);
  EXPECT_FALSE(a_open[0].occluded);
  for (int b = 0; b < 7; ++b) {
    EXPECT_LT(a_blocked[0].gain[b], 0.56 * a_open[0].gain[b]);  // ≥ 5 dB
    if (b > 0) {
      EXPECT_LT(a_blocked[0].gain[b], a_blocked[0].gain[b - 1]);  // low-pass
    }
  }
  const double e_open = energy(open.render(Source{src}, mic, 0)[0]);
  const double e_blocked = energy(blocked.render(Source{src}, mic, 0)[0]);
  EXPECT_LT(e_blocked, 0.3 * e_open);
  // The same box out of the way does nothing.
  s.furniture[0].center = {3, 0.75, 1};
  RirSimulator aside(s, 48000, nullptr, o);
  const auto a_aside = aside.arrivals(Source{src}, mic);
  EXPECT_FALSE(a_aside[0].occluded);
  EXPECT_EQ(a_aside[0].gain, a_open[0].gain);
  EXPECT_TRUE(blocked.inside_furniture({3, 0.5, 3}));
  EXPECT_FALSE(blocked.inside_furniture({3, 2, 3}));
}

TEST(RirSimulator, FurnitureYawMatchesTheGeometryBoxConvention) {
  // The picture renderer uses geometry::YawBox; sound must see the furniture in the same place.
  Scene s = shoebox({6, 3, 6}, 0.2);
  s.furniture.push_back({{3, 0.5, 3}, {2.0, 1.0, 0.4}, 35, "wall"});
  RirSimulator sim(s, 48000, nullptr, mono_dry());
  const geometry::YawBox box{{3, 0.5, 3}, {1.0, 0.5, 0.2}, geometry::deg_to_rad(35)};
  int inside = 0;
  for (int i = 0; i < 60; ++i)
    for (int j = 0; j < 60; ++j) {
      const Vec3 p{1.5 + 0.05 * i, 0.5, 1.5 + 0.05 * j};
      EXPECT_EQ(sim.inside_furniture(p), box.contains(p)) << p.x << " " << p.z;
      inside += box.contains(p);
    }
  EXPECT_GT(inside, 100);
}

TEST(RirSimulator, OcclusionAppliesToReflectionLegs) {
  // A tall wall-like box next to the floor-reflection point blocks only that reflection.
  Scene s = shoebox({6, 3, 6}, 0.2, 0.1, 1, 0.1);
  Material wood;
  s.materials["wood"] = wood;
  s.furniture.push_back({{3, 0.2, 3}, {0.5, 0.4, 0.5}, 0, "wood"});  // low box at the floor point
  const Vec3 src{1, 1.0, 3}, mic{5, 1.0, 3};
  RirSimOptions o = mono_dry();
  o.furniture_reflections = false;
  RirSimulator sim(s, 48000, nullptr, o);
  int occluded = 0;
  for (const Arrival& a : sim.arrivals(Source{src}, mic)) {
    const bool floor_bounce = a.order == 1 && a.direction_world.y < -0.3;
    EXPECT_EQ(a.occluded, floor_bounce) << "order " << a.order;
    occluded += a.occluded;
  }
  EXPECT_EQ(occluded, 1);
}

TEST(RirSimulator, FurnitureTopReflectsLikeAMirror) {
  Scene s = shoebox({6, 3, 6}, 0.2, 0.1, 0, 0.1);
  Material table;
  table.absorption.fill(0.19);
  table.scattering = 0;
  s.materials["table"] = table;
  s.furniture.push_back({{3, 0.4, 3}, {2, 0.8, 1}, 0, "table"});
  RirSimulator sim(s, 48000, nullptr, mono_dry());
  const Vec3 src{2.5, 1.5, 3}, mic{3.5, 1.2, 3.2};
  const auto arr = sim.arrivals(Source{src}, mic);
  int found = 0;
  for (const Arrival& a : arr) {
    if (!a.furniture) continue;
    ++found;
    const Vec3 mirror{src.x, 2 * 0.8 - src.y, src.z};
    EXPECT_NEAR(a.distance_m, geometry::norm(mirror - mic), 1e-9);
    EXPECT_NEAR(a.gain[2] * a.distance_m, 0.9, 1e-9);  // sqrt(1 − 0.19)
    EXPECT_LT(a.direction_world.y, 0);
  }
  EXPECT_EQ(found, 1);  // only the top face sees both points
}

TEST(RirSimulator, LateTailContinuesTheEarlyDecayWithoutAHole) {
  // Smoothed energy envelope in dB should decay roughly linearly through the end of the image set.
  Scene s = shoebox({5, 3, 4}, 0.15, 0.1, 4, 0.8);
  RirSimOptions o;
  o.binaural = false;
  o.air_absorption = false;
  const int fs = 16000;
  RirSimulator sim(s, fs, nullptr, o);
  std::vector<double> env_db;
  const int win = fs / 50;  // 20 ms
  const int n_pose = 6;
  std::vector<double> acc(static_cast<size_t>(0.6 * fs / win), 0.0);
  for (int p = 0; p < n_pose; ++p) {
    const auto h = sim.render(Source{{1 + 0.5 * p, 1.4, 1.2}}, {4.2 - 0.3 * p, 1.5, 3.1}, 0);
    for (size_t w = 0; w < acc.size(); ++w) acc[w] += energy(h[0], w * win, (w + 1) * win);
  }
  const double decay_db_per_s = 60 / sim.eyring_t60()[3];
  // Compare windows from 40 ms on with the expected Eyring line anchored on their mean.
  double offset = 0;
  int n = 0;
  for (size_t w = 2; w < acc.size(); ++w, ++n)
    offset += 10 * std::log10(acc[w]) + decay_db_per_s * (w + 0.5) * win / fs;
  offset /= n;
  for (size_t w = 2; w < acc.size(); ++w) {
    const double db = 10 * std::log10(acc[w]),
                 line = offset - decay_db_per_s * (w + 0.5) * win / fs;
    EXPECT_NEAR(db, line, 2.5) << "window " << w;
  }
}

TEST(RirSimulator, UserErrorsAreReported) {
  Scene s = shoebox({5, 3, 4}, 0.2);
  EXPECT_THROW(RirSimulator(s, 44100, nullptr, RirSimOptions{}), Error);  // binaural needs an HRTF
  EXPECT_THROW(RirSimulator(s, 48000, &kemar44(), RirSimOptions{}), Error);  // rate mismatch
  RirSimulator sim(s, 48000, nullptr, mono_dry());
  EXPECT_THROW(sim.render(Source{{6, 1, 1}}, {1, 1, 1}, 0), Error);
  EXPECT_THROW(sim.render(Source{{1, 1, 1}}, {1, -1, 1}, 0), Error);
  EXPECT_THROW(sim.render(Source{{1, 1, 1}, 0, "hypercardioid"}, {2, 1, 1}, 0), Error);
  Scene bad = s;
  bad.surfaces.floor = "marble";
  try {
    RirSimulator x(bad, 48000, nullptr, mono_dry());
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("surfaces.floor"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("marble"), std::string::npos);
  }
  bad = s;
  bad.furniture.push_back({{1, 1, 1}, {1, -1, 1}, 0, "wall"});
  EXPECT_THROW(RirSimulator(bad, 48000, nullptr, mono_dry()), Error);
}

TEST(RirSimulator, SourceAtTheMicrophoneStaysFinite) {
  Scene s = shoebox({5, 3, 4}, 0.2, 0.1, 2, 0.2);
  RirSimulator sim(s, 48000, nullptr, RirSimOptions{false});
  const auto h = sim.render(Source{{2, 1, 2}}, {2, 1, 2}, 0);
  for (float v : h[0]) ASSERT_TRUE(std::isfinite(v));
  EXPECT_LE(std::abs(h[0][argmax_abs(h[0])]), 10.5f);  // 1/r clamped at 0.1 m
}

}  // namespace
}  // namespace neraf::sim
