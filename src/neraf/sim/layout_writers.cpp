#include "neraf/sim/layout_writers.h"

#include <cmath>
#include <cstdio>

#include "neraf/sim/seeded_random.h"
#include "neraf/util/error.h"

namespace neraf::sim {

using nlohmann::json;

json nerfstudio_transforms(const CameraIntrinsics& k, const std::vector<FrameRecord>& frames,
                           bool orientation_override_none) {
  json j = json::object();
  j["camera_model"] = "OPENCV";
  j["fl_x"] = k.fx;
  j["fl_y"] = k.fy;
  j["cx"] = k.cx;
  j["cy"] = k.cy;
  j["w"] = k.width;
  j["h"] = k.height;
  j["k1"] = 0.0;
  j["k2"] = 0.0;
  j["p1"] = 0.0;
  j["p2"] = 0.0;
  if (orientation_override_none) j["orientation_override"] = "none";
  json list = json::array();
  for (const auto& f : frames) {
    json m = json::array();
    for (const auto& row : f.pose.matrix()) m.push_back(json(row));
    list.push_back({{"file_path", f.file_path}, {"transform_matrix", m}});
  }
  j["frames"] = list;
  return j;
}

std::vector<int> fraction_train_indices(int n, double train_fraction) {
  if (n <= 0) return {};
  const int n_train = static_cast<int>(std::ceil(n * train_fraction));
  std::vector<int> out;
  // numpy.linspace(0, n − 1, n_train, dtype=int): i · step, the last point set to n − 1 exactly,
  // then truncated towards zero.
  const double step = n_train > 1 ? (n - 1.0) / (n_train - 1) : 0.0;
  for (int i = 0; i < n_train; ++i) {
    const double x = (n_train > 1 && i == n_train - 1) ? n - 1.0 : i * step;
    out.push_back(static_cast<int>(x));
  }
  return out;
}

std::string frame_file_name(const std::string& prefix, int index) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%05d", index);
  return "images/" + prefix + "frame_" + buf + ".png";
}

Vec3 world_to_soundspaces(Vec3 w) { return {w.x, -w.z, w.y}; }
Vec3 soundspaces_to_world(Vec3 r) { return {r.x, r.z, -r.y}; }

std::string soundspaces_points_txt(const std::vector<Vec3>& world_points) {
  std::string out;
  char buf[128];
  for (size_t i = 0; i < world_points.size(); ++i) {
    Vec3 p = world_to_soundspaces(world_points[i]);
    for (int a = 0; a < 3; ++a) {
      if (std::abs(p[a]) < 5e-7) p[a] = 0.0;  // no "-0.000000"
    }
    std::snprintf(buf, sizeof buf, "%zu\t%.6f\t%.6f\t%.6f\n", i, p.x, p.y, p.z);
    out += buf;
  }
  return out;
}

std::string soundspaces_rir_name(double heading_deg, int receiver, int source) {
  return std::to_string(static_cast<long>(std::lround(heading_deg))) + "/" +
         std::to_string(receiver) + "_" + std::to_string(source);
}

namespace {

// Flags a seeded random round(fraction · n) of n items (at least 1 when n >= 2).
std::vector<bool> random_test_mask(size_t n, uint64_t seed, double fraction) {
  size_t n_test = static_cast<size_t>(std::lround(fraction * double(n)));
  if (n >= 2) n_test = std::max<size_t>(n_test, 1);
  n_test = std::min(n_test, n);
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  SeededRandom rng(seed);
  rng.shuffle(order);
  std::vector<bool> test(n, false);
  for (size_t i = 0; i < n_test; ++i) test[order[i]] = true;
  return test;
}

}  // namespace

json soundspaces_split(const std::vector<std::string>& names, uint64_t seed, double test_fraction) {
  const auto test = random_test_mask(names.size(), seed, test_fraction);
  json train = json::array(), tst = json::array();
  for (size_t i = 0; i < names.size(); ++i) (test[i] ? tst : train).push_back(names[i]);
  return {{"train", train}, {"test", tst}};
}

std::string raf_id(int index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06d", index);
  return buf;
}

std::string raf_rx_pos(Vec3 p) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f\n", p.x, p.y, p.z);
  return buf;
}

std::string raf_tx_pos(Vec3 p, double yaw_deg) {
  const auto q = geometry::quaternion_from_yaw(yaw_deg);
  char buf[256];
  std::snprintf(buf, sizeof buf, "%.9f,%.9f,%.9f,%.9f,%.6f,%.6f,%.6f\n", q.x, q.y, q.z, q.w, p.x,
                p.y, p.z);
  return buf;
}

json raf_data_split(const std::vector<std::string>& ids, uint64_t seed, double test_fraction) {
  const auto test = random_test_mask(ids.size(), seed, test_fraction);
  json train = json::array(), tst = json::array(), validation = json::array();
  for (size_t i = 0; i < ids.size(); ++i) (test[i] ? tst : train).push_back(ids[i]);
  for (size_t i = 0; i < tst.size(); i += 6) {
    json group = json::array();
    for (size_t k = i; k < std::min(i + 6, tst.size()); ++k) group.push_back(tst[k]);
    validation.push_back(group);
  }
  return {
      {"train", json::array({train})}, {"validation", validation}, {"test", json::array({tst})}};
}

}  // namespace neraf::sim
