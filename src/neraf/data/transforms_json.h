#pragma once
// The text of a nerfstudio transforms.json, parsed and checked without touching the disk and
// without LibTorch (image_set.cpp reads the file and the images; fuzz/ feeds it any bytes): the
// camera model, OPENCV intrinsics global or per frame, each frame's camera-to-world pose, duplicate
// frames, nerfstudio's frame order and its train / eval split rules. Every problem names the file
// and the frame (index and file_path), as the loader reports it.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/data/problem.h"

namespace neraf::data {

struct Intrinsics {  // OPENCV camera model, pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;  // distortion (zero for the simulator)
  double k3 = 0;  // third radial coefficient (nerfstudio OPENCV also carries it; usually 0)
};

// Plausible camera intrinsics, shared by transforms.json and camera files (infer's
// intrinsics_from_json): a focal length of 1e-320 or 9e15 pixels, or a k1 of 1e308, is damage,
// not a camera. Real cameras lie far inside (phones ~3000 px, tele lenses on 8K sensors ~1e5 px;
// OpenCV distortion coefficients are of order 1, fisheye fits a few tens).
constexpr double kMinFocalPixels = 1e-3;
constexpr double kMaxFocalPixels = 1e6;
constexpr double kMaxAbsDistortion = 100;
// "" when the focal lengths (fx, fy) and distortion (k1, k2, k3, p1, p2) of `k` are finite and
// within those bounds, else what is wrong, naming the value with the keys `fx_key`/`fy_key` (a
// transforms.json says fl_x, a camera file fx), e.g. "fl_x is 1e-320, outside 0.001..1e+06 pixels".
std::string intrinsics_problem(const Intrinsics& k, const char* fx_key = "fx",
                               const char* fy_key = "fy");

namespace detail {

// Largest |camera position| accepted (the scene's units, metres for every dataset neraf reads),
// the bound of every other pose file (rir_check.h).
constexpr double kMaxAbsTranslation = 1e4;
// Largest image side accepted in w / h (pixels), as the run manifests bound it (infer/run.h).
constexpr int kMaxImageSide = 16384;

struct TransformsFrame {
  int json_index = 0;     // index in transforms.json "frames" (what users can find in the file)
  std::string file_path;  // as written in the json
  std::string path;       // resolved against the data folder, lexically normal
  Intrinsics intr;
  bool has_size = false;   // w/h given (globally or per frame)
  double pose[3][4] = {};  // camera-to-world rows 0..2
  bool pose_ok = false;
  // Filled by the image checks (image_set.cpp), not by the parser.
  bool image_ok = false;
  int image_w = 0, image_h = 0;
};

// "frames[3] (images/train_0003.png)"
std::string frame_name(const TransformsFrame& f);

struct Transforms {
  std::string json_path;                // the file, for messages
  std::string data_dir;                 // the folder frame paths are relative to
  nlohmann::json meta;                  // the whole file
  std::vector<TransformsFrame> frames;  // every frame with a file_path, sorted like nerfstudio
  std::string orientation;              // "up" | "none" ("" when the file has no frames)
};

// Parses `text`, the contents of `json_path`, as nerfstudio's NerfstudioDataParser does: frames
// sorted by file path (resolved against `data_dir`); per-frame intrinsics used only where the
// global one is absent; NaN / Infinity (Python's json writes them) read as null, so the pose check
// names the frame. `orientation` is ImageLoadOptions::orientation ("" = the file's
// orientation_override, else "up"). Problems are appended; a frame with a bad pose or bad
// intrinsics is kept (pose_ok false for a bad pose: the split still counts it), a duplicate frame
// is dropped.
Transforms parse_transforms_json(const std::string& text, const std::string& json_path,
                                 const std::string& data_dir, const std::string& orientation,
                                 ProblemList& problems);

// Splits the frame indices of `t` into train / eval following nerfstudio's rules and sets `mode`
// to the rule used: the file's train_filenames / val_filenames (or test_filenames) lists
// ("lists"), else `eval_mode` ("auto": "filename" when every file name contains "train_" or
// "eval_", else "fraction"; ImageLoadOptions). neraf::Error for an unknown eval_mode or a
// train_fraction outside (0, 1] (the caller's options, not the file).
void split_transforms(const Transforms& t, const std::string& eval_mode, double train_fraction,
                      ProblemList& problems, std::vector<int64_t>& train,
                      std::vector<int64_t>& eval, std::string& mode);

}  // namespace detail
}  // namespace neraf::data
