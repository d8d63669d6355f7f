// Layout formatting: points.txt axis convention, split ratios, RAF quaternions, transforms.json,
// PNG and WAV bytes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "neraf/geometry/pose.h"
#include "neraf/sim/layout_writers.h"
#include "neraf/util/error.h"

namespace neraf::sim {
namespace {

using nlohmann::json;

std::filesystem::path temp_dir(const std::string& name) {
  auto d =
      std::filesystem::temp_directory_path() / ("neraf_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

TEST(LayoutFormat, PointsTxtMapsBackThroughNerafsAxisConvention) {
  const std::vector<Vec3> world = {{0.5, 1.5, 0.25}, {3.25, 1.2, 2.75}, {1.0, 0.0, 0.0}};
  const std::string text = soundspaces_points_txt(world);
  std::istringstream in(text);
  std::string line;
  size_t n = 0;
  while (std::getline(in, line)) {
    // Tab-separated "idx x y z".
    std::vector<std::string> fields;
    std::stringstream ls(line);
    std::string f;
    while (std::getline(ls, f, '\t')) fields.push_back(f);
    ASSERT_EQ(fields.size(), 4u) << line;
    EXPECT_EQ(std::stoul(fields[0]), n);
    const double x = std::stod(fields[1]), y = std::stod(fields[2]), z = std::stod(fields[3]);
    // NeRAF's SoundSpacesDataParser: position = [x, z, −y] — must give our y-up world point back.
    EXPECT_NEAR(x, world[n].x, 1e-6);
    EXPECT_NEAR(z, world[n].y, 1e-6);
    EXPECT_NEAR(-y, world[n].z, 1e-6);
    ++n;
  }
  EXPECT_EQ(n, world.size());
  EXPECT_EQ(text.find("-0.000000"), std::string::npos);
  const Vec3 r = soundspaces_to_world(world_to_soundspaces({1, 2, 3}));
  EXPECT_EQ(r.x, 1);
  EXPECT_EQ(r.y, 2);
  EXPECT_EQ(r.z, 3);
}

TEST(LayoutFormat, SoundSpacesNamesAndSplit) {
  EXPECT_EQ(soundspaces_rir_name(90, 12, 3), "90/12_3");
  EXPECT_EQ(soundspaces_rir_name(0, 0, 41), "0/0_41");
  std::vector<std::string> names;
  for (int i = 0; i < 1000; ++i) names.push_back(soundspaces_rir_name(90 * (i % 4), i / 4, 7));
  const json split = soundspaces_split(names, 5);
  ASSERT_TRUE(split.contains("train"));
  ASSERT_TRUE(split.contains("test"));
  EXPECT_EQ(split.size(), 2u);
  EXPECT_EQ(split["train"].size(), 900u);
  EXPECT_EQ(split["test"].size(), 100u);
  std::set<std::string> all;
  for (const auto& e : split["train"]) all.insert(e.get<std::string>());
  for (const auto& e : split["test"]) all.insert(e.get<std::string>());
  EXPECT_EQ(all.size(), 1000u);                   // disjoint and complete
  EXPECT_EQ(soundspaces_split(names, 5), split);  // seeded
  EXPECT_NE(soundspaces_split(names, 6)["test"], split["test"]);
  // The test entries are spread over the whole list, not a block.
  std::set<int> rows;
  for (const auto& e : split["test"]) {
    const auto it = std::find(names.begin(), names.end(), e.get<std::string>());
    rows.insert(static_cast<int>(it - names.begin()) / 100);
  }
  EXPECT_GE(rows.size(), 8u);
  // Tiny sets still get a test entry.
  EXPECT_EQ(soundspaces_split({"0/0_1", "0/1_1", "0/2_1"}, 1)["test"].size(), 1u);
}

// scipy's Rotation.from_quat([x, y, z, w]).as_euler('yxz')[0] in degrees, written from the
// definition: extrinsic y, x, z  ⇒  R = Rz(γ)·Rx(β)·Ry(α), whose third row is
// (−cos β sin α, sin β, cos β cos α), so α = atan2(−R[2][0], R[2][2]).
double scipy_yaw_yxz(double x, double y, double z, double w) {
  const double n = std::sqrt(x * x + y * y + z * z + w * w);
  x /= n, y /= n, z /= n, w /= n;
  const double r20 = 2 * (x * z - w * y);
  const double r22 = 1 - 2 * (x * x + y * y);
  return std::atan2(-r20, r22) * 180 / M_PI;
}

TEST(LayoutFormat, RafTxPosQuaternionGivesTheYawBack) {
  for (double yaw : {0.0, 30.0, 90.0, 135.0, 179.0, 180.0, 225.0, 270.0, -45.0, 359.0}) {
    const std::string line = raf_tx_pos({1.5, 1.25, 2.75}, yaw);
    ASSERT_EQ(line.back(), '\n');
    std::vector<double> v;
    std::stringstream ss(line);
    std::string f;
    while (std::getline(ss, f, ',')) v.push_back(std::stod(f));
    ASSERT_EQ(v.size(), 7u) << line;
    const double got = scipy_yaw_yxz(v[0], v[1], v[2], v[3]);
    double want = std::fmod(yaw, 360.0);
    if (want > 180) want -= 360;
    if (want <= -180) want += 360;
    EXPECT_NEAR(std::remainder(got - want, 360.0), 0.0, 1e-6) << yaw;
    // NeRAF rounds to whole degrees: the same heading comes back.
    EXPECT_EQ(std::lround(std::remainder(std::round(got) - yaw, 360.0)), 0) << yaw;
    EXPECT_NEAR(v[4], 1.5, 1e-9);
    EXPECT_NEAR(v[5], 1.25, 1e-9);
    EXPECT_NEAR(v[6], 2.75, 1e-9);
    // The quaternion turns the source's forward axis (−z) into our forward(yaw).
    const auto f_world = geometry::rotate(geometry::Quaternion{v[0], v[1], v[2], v[3]}, {0, 0, -1});
    const auto f_yaw = geometry::heading_forward(yaw);
    EXPECT_NEAR(f_world.x, f_yaw.x, 1e-8);
    EXPECT_NEAR(f_world.z, f_yaw.z, 1e-8);
  }
  EXPECT_EQ(raf_rx_pos({1, 2.5, 0.125}), "1.000000,2.500000,0.125000\n");
  EXPECT_EQ(raf_id(12), "000012");
  EXPECT_EQ(raf_id(123456), "123456");
}

TEST(LayoutFormat, RafDataSplit) {
  std::vector<std::string> ids;
  for (int i = 0; i < 200; ++i) ids.push_back(raf_id(i));
  const json s = raf_data_split(ids, 3);
  ASSERT_EQ(s["train"].size(), 1u);
  ASSERT_EQ(s["test"].size(), 1u);
  EXPECT_EQ(s["train"][0].size(), 180u);
  EXPECT_EQ(s["test"][0].size(), 20u);
  size_t in_validation = 0;
  for (const auto& group : s["validation"]) {
    EXPECT_LE(group.size(), 6u);
    in_validation += group.size();
  }
  EXPECT_EQ(in_validation, 20u);
  std::set<std::string> all;
  for (const auto& e : s["train"][0]) all.insert(e.get<std::string>());
  for (const auto& e : s["test"][0]) all.insert(e.get<std::string>());
  EXPECT_EQ(all.size(), 200u);
  EXPECT_EQ(s["test"][0][0].get<std::string>().size(), 6u);
}

TEST(LayoutFormat, FractionSplitMatchesNerfstudio) {
  // numpy.linspace(0, 9, 9, dtype=int) = [0 1 2 3 4 5 6 7 9]: image 8 is the eval image.
  EXPECT_EQ(fraction_train_indices(10), (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 9}));
  // numpy.linspace(0, 4, 5) = everything: ceil(0.9·5) = 5 train images, none for eval.
  EXPECT_EQ(fraction_train_indices(5), (std::vector<int>{0, 1, 2, 3, 4}));
  // The published RAF counts: 210 → 189 train, 840 → 756 train.
  EXPECT_EQ(fraction_train_indices(210).size(), 189u);
  EXPECT_EQ(fraction_train_indices(840).size(), 756u);
  const auto t = fraction_train_indices(60);
  EXPECT_EQ(t.size(), 54u);
  EXPECT_EQ(std::set<int>(t.begin(), t.end()).size(), 54u);
  EXPECT_EQ(t.front(), 0);
  EXPECT_EQ(t.back(), 59);
}

TEST(LayoutFormat, TransformsJson) {
  CameraIntrinsics k;
  k.width = 96;
  k.height = 64;
  k.fx = k.fy = 48;
  k.cx = 48;
  k.cy = 32;
  const auto pose = geometry::look_at({1, 1.5, 2}, {2, 1.5, 2});
  const json t = nerfstudio_transforms(k, {{frame_file_name("train_", 3), pose}}, true);
  EXPECT_EQ(t["camera_model"], "OPENCV");
  EXPECT_EQ(t["w"], 96);
  EXPECT_EQ(t["h"], 64);
  EXPECT_EQ(t["fl_x"], 48.0);
  EXPECT_EQ(t["fl_y"], 48.0);
  EXPECT_EQ(t["cx"], 48.0);
  EXPECT_EQ(t["cy"], 32.0);
  for (const char* d : {"k1", "k2", "p1", "p2"}) EXPECT_EQ(t[d], 0.0) << d;
  EXPECT_EQ(t["orientation_override"], "none");
  ASSERT_EQ(t["frames"].size(), 1u);
  const auto& f = t["frames"][0];
  EXPECT_EQ(f["file_path"], "images/train_frame_00003.png");
  const auto& m = f["transform_matrix"];
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[3], json({0.0, 0.0, 0.0, 1.0}));
  // Column 3 = position; column 2 = −forward (OpenGL cameras look along −z); column 1 = up.
  EXPECT_DOUBLE_EQ(m[0][3].get<double>(), 1);
  EXPECT_DOUBLE_EQ(m[1][3].get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(m[0][2].get<double>(), -1);
  EXPECT_DOUBLE_EQ(m[1][1].get<double>(), 1);
  EXPECT_FALSE(nerfstudio_transforms(k, {}, false).contains("orientation_override"));
  EXPECT_EQ(frame_file_name("", 12), "images/frame_00012.png");
  EXPECT_EQ(frame_file_name("eval_", 0), "images/eval_frame_00000.png");
}

}  // namespace
}  // namespace neraf::sim
