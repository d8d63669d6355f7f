#include "neraf/sim/hrtf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "neraf/util/error.h"
#include "rir_test_util.h"

namespace neraf::sim {
namespace {

using testing::energy;

size_t first_above(const std::vector<float>& x, double fraction) {
  float peak = 0;
  for (float v : x) peak = std::max(peak, std::abs(v));
  for (size_t i = 0; i < x.size(); ++i)
    if (std::abs(x[i]) >= fraction * peak) return i;
  return x.size();
}

TEST(Hrtf, LoadsKemarAtTheRequestedRate) {
  const Hrtf h44(44100);
  EXPECT_EQ(h44.sample_rate(), 44100);
  EXPECT_EQ(h44.filter_length(), 512);  // MIT KEMAR: 512 taps at 44.1 kHz
  EXPECT_EQ(h44.num_directions(), 710);
  const Hrtf h48(48000);
  EXPECT_GT(h48.filter_length(), 512);  // resampled by libmysofa
  for (int i = 0; i < h44.num_directions(); ++i)
    EXPECT_NEAR(geometry::norm(h44.direction(i)), 1.0, 1e-5);
}

TEST(Hrtf, LeftSourceIsLouderAndEarlierInTheLeftEar) {
  const Hrtf h(44100);
  std::vector<float> l, r;
  double dl = -1, dr = -1;
  h.lookup({0, 1, 0}, l, r, dl, dr);  // head frame: +y = left
  ASSERT_EQ(static_cast<int>(l.size()), h.filter_length());
  EXPECT_EQ(dl, 0.0);  // default.sofa keeps the ITD inside the IRs
  EXPECT_EQ(dr, 0.0);
  EXPECT_GT(energy(l), 4 * energy(r));
  EXPECT_LT(first_above(l, 0.1) + 10, first_above(r, 0.1));  // ITD ≈ 0.6 ms ≈ 28 samples
  h.lookup({0, -1, 0}, l, r, dl, dr);
  EXPECT_GT(energy(r), 4 * energy(l));
  // Frontal: the two ears nearly agree.
  h.lookup({1, 0, 0}, l, r, dl, dr);
  EXPECT_NEAR(energy(l) / energy(r), 1.0, 0.3);
  EXPECT_LE(
      std::abs(static_cast<long>(first_above(l, 0.1)) - static_cast<long>(first_above(r, 0.1))), 2);
}

TEST(Hrtf, NearestDirectionIsTheClosestMeasurement) {
  const Hrtf h(44100);
  const geometry::Vec3 d = geometry::normalized({0.3, 0.5, 0.2});
  const int i = h.nearest_index(d);
  for (int j = 0; j < h.num_directions(); ++j)
    EXPECT_GE(geometry::dot(h.direction(i), d), geometry::dot(h.direction(j), d) - 1e-12);
  EXPECT_GT(geometry::dot(h.direction(i), d), std::cos(geometry::deg_to_rad(8)));
}

TEST(Hrtf, WorldToHeadFollowsTheSceneHeadingConvention) {
  // yaw 0: forward = −z, left = −x, up = +y.
  auto near = [](geometry::Vec3 a, geometry::Vec3 b) {
    return std::abs(a.x - b.x) < 1e-12 && std::abs(a.y - b.y) < 1e-12 &&
           std::abs(a.z - b.z) < 1e-12;
  };
  EXPECT_TRUE(near(Hrtf::world_to_head({0, 0, -1}, 0), {1, 0, 0}));
  EXPECT_TRUE(near(Hrtf::world_to_head({-1, 0, 0}, 0), {0, 1, 0}));
  EXPECT_TRUE(near(Hrtf::world_to_head({0, 1, 0}, 0), {0, 0, 1}));
  // yaw 90: forward = −x, left = +z.
  EXPECT_TRUE(near(Hrtf::world_to_head({-1, 0, 0}, 90), {1, 0, 0}));
  EXPECT_TRUE(near(Hrtf::world_to_head({0, 0, 1}, 90), {0, 1, 0}));
  // yaw 180: forward = +z, left = +x.
  EXPECT_TRUE(near(Hrtf::world_to_head({1, 0, 0}, 180), {0, 1, 0}));
}

TEST(Hrtf, MissingFileIsAUserErrorNamingTheFile) {
  try {
    Hrtf h(44100, "/nonexistent/kemar.sofa");
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/kemar.sofa"), std::string::npos);
  }
}

TEST(Hrtf, NonSofaFileIsAUserError) {
  const std::string path = ::testing::TempDir() + "/not_a_sofa.sofa";
  std::ofstream(path) << "this is not an HDF5 file\n";
  try {
    Hrtf h(44100, path);
    FAIL() << "expected neraf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
}

}  // namespace
}  // namespace neraf::sim
