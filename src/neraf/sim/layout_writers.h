#pragma once
// Writers of the dataset layouts NeRAF reads (docs/SCENE_FORMAT.md "Output layouts";
// neraf-reference.md §3.2 SoundSpaces, §3.3 RAF) and of the nerfstudio transforms.json.
// Pure formatting functions (tested on their own) + a few writers; every file is written
// atomically.
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/geometry/pose.h"
#include "neraf/sim/cameras.h"
#include "neraf/sim/image_renderer.h"

namespace neraf::sim {

constexpr int kSoundSpacesSampleRate = 44100;  // binaural_rirs/*.wav
constexpr int kRafSampleRate = 48000;          // data/*/rir.wav

// ---------------------------------------------------------------- nerfstudio (vision half)

struct FrameRecord {
  std::string file_path;  // relative to the dataset root, e.g. "images/train_frame_00000.png"
  geometry::CameraPose pose;
};

// transforms.json: camera_model "OPENCV", shared intrinsics fl_x, fl_y, cx, cy, w, h,
// k1 = k2 = p1 = p2 = 0, frames [{file_path, transform_matrix (4×4 camera-to-world, OpenGL)}].
// `orientation_override_none` adds "orientation_override": "none" (NeRAF's SoundSpaces files do).
nlohmann::json nerfstudio_transforms(const CameraIntrinsics& k,
                                     const std::vector<FrameRecord>& frames,
                                     bool orientation_override_none);

// nerfstudio's eval_mode "fraction" rule (what NeRAF uses for RAF): with n images the train set is
// linspace(0, n − 1, ceil(n · fraction)) truncated to integers, the eval set is the rest.
std::vector<int> fraction_train_indices(int n, double train_fraction = 0.9);

// "images/train_frame_00012.png" style names (5 digits).
std::string frame_file_name(const std::string& prefix, int index);

// ---------------------------------------------------------------- SoundSpaces (NeRAF layout)

// metadata/points.txt holds SoundSpaces' z-up coordinates; NeRAF maps a row (x, y, z) to the
// y-up position [x, z, −y]. So a world point (X, Y, Z) (y up, scene.h) is written as (X, −Z, Y).
Vec3 world_to_soundspaces(Vec3 world);
Vec3 soundspaces_to_world(Vec3 row);  // NeRAF's mapping [x, z, −y]

// "idx\tx\ty\tz\n" per point (6 decimals), idx = 0, 1, ...
std::string soundspaces_points_txt(const std::vector<Vec3>& world_points);

// "<heading>/<receiver>_<source>" (heading in whole degrees) — the split.json entry; the file is
// binaural_rirs/<entry>.wav.
std::string soundspaces_rir_name(double heading_deg, int receiver, int source);

// {"train": [...], "test": [...]}: a seeded random round(test_fraction · n) entries (at least 1
// when n >= 2) go to "test"; each list keeps the input order.
nlohmann::json soundspaces_split(const std::vector<std::string>& names, uint64_t seed,
                                 double test_fraction = 0.1);

// ---------------------------------------------------------------- RAF

std::string raf_id(int index);          // 6 digits: "000012"
std::string raf_rx_pos(Vec3 position);  // "x,y,z"
// "qx,qy,qz,qw,x,y,z": the source orientation as a real-LAST quaternion, the rotation R_y(yaw)
// about +y that turns the forward axis −z into forward(yaw); scipy's
// R.from_quat(q).as_euler('yxz', degrees=True)[0] gives yaw back (wrapped to (−180, 180]).
std::string raf_tx_pos(Vec3 position, double yaw_deg);

// metadata/data-split.json: {"train": [[ids]], "validation": [[6 ids], ...], "test": [[ids]]}.
// A seeded random round(test_fraction · n) ids (at least 1 when n >= 2) are "test"; "validation"
// repeats the test ids in groups of 6 (RAF's format; NeRAF never reads it).
nlohmann::json raf_data_split(const std::vector<std::string>& ids, uint64_t seed,
                              double test_fraction = 0.1);

}  // namespace neraf::sim
