// nerfstudio transforms.json loading: splits, intrinsics, pixels, pose normalisation (nerfstudio
// dataparser semantics) and the errors that name the frame.
#include "neraf/data/image_set.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fixtures.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::data {
namespace {

using testing::NerfstudioScene;
using testing::TempDir;

ImageLoadOptions quiet_images() {
  ImageLoadOptions o;
  o.progress = false;
  return o;
}

std::string error_of(const std::string& dir, ImageLoadOptions o = quiet_images()) {
  try {
    load_transforms_json(dir, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ImageSet, FilenameSplitIntrinsicsAndPixels) {
  TempDir dir;
  NerfstudioScene scene;
  scene.write(dir.path());
  const ImageSet set = load_transforms_json(dir.path(), quiet_images());
  EXPECT_EQ(set.eval_mode, "filename");
  // Frames are sorted by path: eval_0000 < train_0000 < train_0001 < train_0002.
  ASSERT_EQ(set.train.size(), 3);
  ASSERT_EQ(set.eval.size(), 1);
  EXPECT_EQ(set.train.files[0], dir / "images/train_0000.png");
  EXPECT_EQ(set.train.files[2], dir / "images/train_0002.png");
  EXPECT_EQ(set.eval.files[0], dir / "images/eval_0000.png");
  EXPECT_EQ(set.train.appearance_ids, (std::vector<int64_t>{0, 1, 2}));
  EXPECT_EQ(set.eval.appearance_ids, (std::vector<int64_t>{-1}));
  const Intrinsics& k = set.train.intrinsics[1];
  EXPECT_EQ(k.fx, 10.0);
  EXPECT_EQ(k.fy, 11.0);
  EXPECT_EQ(k.cx, 6.0);
  EXPECT_EQ(k.cy, 4.0);
  EXPECT_EQ(k.width, 12);
  EXPECT_EQ(k.height, 8);
  EXPECT_EQ(k.k1, 0.01);
  EXPECT_EQ(k.k2, 0.0);
  ASSERT_EQ(set.train.images.sizes(), (std::vector<int64_t>{3, 8, 12, 3}));
  EXPECT_EQ(set.train.images.scalar_type(), torch::kUInt8);
  // train_0002 is frame 3 of the json; check a few pixels.
  auto px = set.train.images.accessor<uint8_t, 4>();
  for (const auto& [x, y, c] : {std::array<int, 3>{0, 0, 0}, {11, 7, 2}, {5, 3, 1}})
    EXPECT_EQ(px[2][y][x][c], NerfstudioScene::pixel(3, x, y, c));
  auto ev = set.eval.images.accessor<uint8_t, 4>();
  EXPECT_EQ(ev[0][7][11][2], NerfstudioScene::pixel(2, 11, 7, 2));
}

TEST(ImageSet, FractionSplitUsesNumpyLinspaceTruncation) {
  TempDir dir;
  NerfstudioScene scene;
  scene.names.clear();
  for (int i = 0; i < 10; ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "images/frame_%05d.png", i);
    scene.names.push_back(buf);
  }
  scene.write(dir.path());
  const ImageSet set = load_transforms_json(dir.path(), quiet_images());
  EXPECT_EQ(set.eval_mode, "fraction");
  // ceil(0.9·10) = 9 train; linspace(0, 9, 9) = 0, 1.125, ..., 7.875, 9 -> ints 0..7, 9.
  ASSERT_EQ(set.train.size(), 9);
  ASSERT_EQ(set.eval.size(), 1);
  EXPECT_EQ(set.eval.files[0], dir / "images/frame_00008.png");
  EXPECT_EQ(set.train.files[8], dir / "images/frame_00009.png");
}

TEST(ImageSet, PoseNormalisationMatchesNerfstudio) {
  // Two cameras, identity rotations (up = +y), at x = 1 and x = 3.
  // "up": rotation taking +y to +z = Rx(90°) = [[1,0,0],[0,0,-1],[0,1,0]]; centre (2,0,0);
  // oriented positions (∓1, 0, 0); max |t| = 1 -> scale 1.
  TempDir dir;
  NerfstudioScene scene;
  scene.names = {"a.png", "b.png"};
  scene.write(dir.path());
  const std::string json =
      R"({"fl_x": 10, "fl_y": 10, "cx": 6, "cy": 4, "w": 12, "h": 8, "frames": [
      {"file_path": "a.png", "transform_matrix": [[1,0,0,1],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
      {"file_path": "b.png", "transform_matrix": [[1,0,0,3],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})";
  testing::write_text(dir / "transforms.json", json);
  ImageLoadOptions o = quiet_images();
  o.eval_mode = "fraction";
  o.train_fraction = 1.0;
  const ImageSet set = load_transforms_json(dir.path(), o);
  ASSERT_EQ(set.train.size(), 2);
  const torch::Tensor want0 =
      torch::tensor({1.f, 0.f, 0.f, -1.f, 0.f, 0.f, -1.f, 0.f, 0.f, 1.f, 0.f, 0.f}).view({3, 4});
  const torch::Tensor want1 =
      torch::tensor({1.f, 0.f, 0.f, 1.f, 0.f, 0.f, -1.f, 0.f, 0.f, 1.f, 0.f, 0.f}).view({3, 4});
  EXPECT_TRUE(torch::allclose(set.train.camera_to_world[0], want0, 0, 1e-6))
      << set.train.camera_to_world;
  EXPECT_TRUE(torch::allclose(set.train.camera_to_world[1], want1, 0, 1e-6));
  EXPECT_DOUBLE_EQ(set.world_scale, 1.0);
  // The stored transform maps dataset points the same way: (3,0,0) -> (1,0,0), (2,5,0) -> (0,0,5).
  const torch::Tensor p =
      torch::tensor({3.0, 0.0, 0.0, 2.0, 5.0, 0.0}, torch::kFloat64).view({2, 3});
  const torch::Tensor q = to_normalized_world(set, p);
  EXPECT_TRUE(torch::allclose(
      q, torch::tensor({1.0, 0.0, 0.0, 0.0, 0.0, 5.0}, torch::kFloat64).view({2, 3}), 0, 1e-12))
      << q;
}

TEST(ImageSet, OrientationOverrideNoneAndAutoScale) {
  TempDir dir;
  NerfstudioScene scene;
  scene.extra_top_level = "\"orientation_override\": \"none\",";
  scene.write(dir.path());
  const ImageSet set = load_transforms_json(dir.path(), quiet_images());
  // No rotation: R = I; translation −mean; scale 1 / max |t|.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      EXPECT_DOUBLE_EQ(set.world_transform[i][j].item<double>(), i == j ? 1.0 : 0.0);
  double mean[3] = {0, 0, 0};
  for (size_t f = 0; f < 4; ++f)
    for (int r = 0; r < 3; ++r) mean[r] += NerfstudioScene::pose(f)[r][3] / 4;
  double max_abs = 0;
  for (size_t f = 0; f < 4; ++f)
    for (int r = 0; r < 3; ++r)
      max_abs = std::max(max_abs, std::abs(NerfstudioScene::pose(f)[r][3] - mean[r]));
  EXPECT_NEAR(set.world_scale, 1.0 / max_abs, 1e-12);
  // Frame 3 (train_0002, the last train frame after sorting): rotation unchanged, t normalised.
  const auto p3 = NerfstudioScene::pose(3);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(set.train.camera_to_world[2][r][c].item<float>(), p3[r][c], 1e-6);
    EXPECT_NEAR(set.train.camera_to_world[2][r][3].item<float>(), (p3[r][3] - mean[r]) / max_abs,
                1e-6);
  }
  // All normalised translations within [-1, 1], one of them at ±1.
  const torch::Tensor t = torch::cat({set.train.camera_to_world, set.eval.camera_to_world})
                              .index({torch::indexing::Slice(), torch::indexing::Slice(), 3});
  EXPECT_NEAR(t.abs().max().item<float>(), 1.0f, 1e-6);
}

TEST(ImageSet, UpOrientationMapsTheMeanUpToZ) {
  TempDir dir;
  NerfstudioScene scene;
  scene.write(dir.path());
  const ImageSet set = load_transforms_json(dir.path(), quiet_images());
  // Every camera's y axis is +y in the dataset; after orientation it is +z.
  const torch::Tensor all = torch::cat({set.train.camera_to_world, set.eval.camera_to_world});
  for (int64_t i = 0; i < all.size(0); ++i) {
    EXPECT_NEAR(all[i][0][1].item<float>(), 0.0f, 1e-6);
    EXPECT_NEAR(all[i][1][1].item<float>(), 0.0f, 1e-6);
    EXPECT_NEAR(all[i][2][1].item<float>(), 1.0f, 1e-6);
  }
}

TEST(ImageSet, ErrorsNameTheFrameAndFile) {
  {  // image size differs from the intrinsics
    TempDir dir;
    NerfstudioScene scene;
    scene.write(dir.path());
    scene.write_image(dir.path(), 1, 10, 8);  // train_0001 now 10x8
    const std::string e = error_of(dir.path());
    EXPECT_NE(e.find("frames[1] (images/train_0001.png)"), std::string::npos) << e;
    EXPECT_NE(e.find("10x8"), std::string::npos) << e;
    EXPECT_NE(e.find("12x8"), std::string::npos) << e;
  }
  {  // missing image
    TempDir dir;
    NerfstudioScene scene;
    scene.write(dir.path());
    fs::remove(dir / "images/eval_0000.png");
    const std::string e = error_of(dir.path());
    EXPECT_NE(e.find("frames[2] (images/eval_0000.png)"), std::string::npos) << e;
    EXPECT_NE(e.find("does not exist"), std::string::npos) << e;
  }
  {  // unreadable image
    TempDir dir;
    NerfstudioScene scene;
    scene.write(dir.path());
    testing::write_text(dir / "images/train_0000.png", "garbage");
    const std::string e = error_of(dir.path());
    EXPECT_NE(e.find("frames[0]"), std::string::npos) << e;
    EXPECT_NE(e.find("cannot be read"), std::string::npos) << e;
  }
  {  // NaN pose (Python's json writes NaN), scaled rotation, mirrored rotation
    TempDir dir;
    NerfstudioScene scene;
    scene.write(dir.path());
    std::string j = scene.json_text();
    // frames[0] pose row 0 starts with cos(0) = 1: replace the first transform by NaN.
    const size_t at = j.find("\"transform_matrix\": [[") + std::strlen("\"transform_matrix\": [[");
    j.replace(at, j.find(',', at) - at, "NaN");
    testing::write_text(dir / "transforms.json", j);
    std::string e = error_of(dir.path());
    EXPECT_NE(e.find("frames[0] (images/train_0000.png)"), std::string::npos) << e;
    EXPECT_NE(e.find("NaN"), std::string::npos) << e;

    const std::string scaled =
        R"({"fl_x": 10, "fl_y": 10, "cx": 6, "cy": 4, "w": 12, "h": 8, "frames": [
        {"file_path": "images/train_0000.png", "transform_matrix": [[2,0,0,1],[0,2,0,0],[0,0,2,0],[0,0,0,1]]},
        {"file_path": "images/train_0001.png", "transform_matrix": [[-1,0,0,3],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})";
    testing::write_text(dir / "transforms.json", scaled);
    ProblemList problems;
    check_transforms_json(dir.path(), quiet_images(), problems);
    ASSERT_EQ(problems.num_errors(), 2) << problems.items()[0].to_string();
    EXPECT_NE(problems.items()[0].what.find("frames[0]"), std::string::npos);
    EXPECT_NE(problems.items()[0].what.find("not a rotation"), std::string::npos);
    EXPECT_NE(problems.items()[1].what.find("frames[1]"), std::string::npos);
    EXPECT_NE(problems.items()[1].what.find("det -1"), std::string::npos)
        << problems.items()[1].what;
  }
  {  // empty train split: every file is an eval_ frame
    TempDir dir;
    NerfstudioScene scene;
    scene.names = {"images/eval_0000.png", "images/eval_0001.png"};
    scene.write(dir.path());
    const std::string e = error_of(dir.path());
    EXPECT_NE(e.find("train split is empty"), std::string::npos) << e;
  }
}

TEST(ImageSet, CollectsEveryProblemBeforeThrowing) {
  TempDir dir;
  NerfstudioScene scene;
  scene.write(dir.path());
  fs::remove(dir / "images/train_0000.png");
  fs::remove(dir / "images/train_0001.png");
  const std::string e = error_of(dir.path());
  EXPECT_NE(e.find("and 1 more error"), std::string::npos) << e;
  EXPECT_NE(e.find("neraf info"), std::string::npos) << e;
}

TEST(ImageSet, RafSizedFractionSplitCounts) {
  // 840 / 210 frames -> 756 / 189 train (the counts baked into the released checkpoints).
  for (const auto& [n, want] : {std::pair<int, int64_t>{840, 756}, {210, 189}}) {
    TempDir dir;
    NerfstudioScene scene;
    scene.names = {"images/frame_00000.png"};
    scene.write(dir.path());
    // One file per frame: the same image listed twice is an error (a duplicate frame).
    std::string frames;
    for (int i = 0; i < n; ++i) {
      char name[64];
      std::snprintf(name, sizeof name, "images/frame_%05d.png", i);
      if (i > 0) fs::copy_file(dir / "images/frame_00000.png", dir / name);
      frames += std::string(i ? "," : "") + R"({"file_path": ")" + name +
                R"(", "transform_matrix": [[1,0,0,)" + std::to_string(i) +
                "],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}";
    }
    testing::write_text(
        dir / "transforms.json",
        R"({"fl_x": 10, "fl_y": 10, "cx": 6, "cy": 4, "w": 12, "h": 8, "frames": [)" + frames +
            "]}");
    ImageLoadOptions o = quiet_images();
    o.load_pixels = false;
    const ImageSet set = load_transforms_json(dir.path(), o);
    EXPECT_EQ(set.train.size(), want);
    EXPECT_EQ(set.eval.size(), n - want);
  }
}

}  // namespace
}  // namespace neraf::data
