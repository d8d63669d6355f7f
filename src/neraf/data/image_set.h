#pragma once
// Posed images of one scene (the vision half of a dataset), as the radiance field consumes them.
// Poses are camera-to-world in the nerfstudio/OpenGL convention (x right, y up, camera looks
// along −z), already normalised by `world_transform` (nerfstudio dataparser: orientation,
// centring on the poses, auto-scale so that max |t| = 1).
#include <torch/torch.h>

#include <string>
#include <vector>

#include "neraf/data/problem.h"
#include "neraf/data/transforms_json.h"  // Intrinsics

namespace neraf::data {

struct ImageSplit {
  std::vector<std::string> files;       // image paths, one per frame
  std::vector<Intrinsics> intrinsics;   // one per frame
  torch::Tensor camera_to_world;        // [N, 3, 4] float32, normalised world frame
  torch::Tensor images;                 // [N, H, W, 3] uint8 (all frames share H, W)
  std::vector<int64_t> appearance_ids;  // train: 0..N-1 (embedding index); eval: -1 (use the mean)

  int64_t size() const { return static_cast<int64_t>(files.size()); }
};

struct ImageSet {
  ImageSplit train, eval;
  // Maps dataset world coordinates to the normalised frame: p_norm = scale * (R p + t).
  torch::Tensor world_transform;  // [3, 4] float64: [R | t] before scaling
  double world_scale = 1.0;
  std::string source;     // the transforms.json it was read from
  std::string eval_mode;  // the split rule used: "filename" | "fraction" | "lists"
};

struct ImageLoadOptions {
  // "auto": "filename" when every frame's file name contains "train_" or "eval_", else
  // "fraction". "filename" | "fraction" force one rule. transforms.json's own
  // "train_filenames"/"val_filenames"/"test_filenames" lists win over both (nerfstudio does so).
  std::string eval_mode = "auto";
  double train_fraction = 0.9;  // "fraction": train = floor(linspace(0, N-1, ceil(f·N)))
  // "" = transforms.json's "orientation_override" if present, else "up"; or "up" | "none".
  std::string orientation;
  bool auto_scale = true;   // scale so that the largest |t| component of the poses is 1
  bool load_pixels = true;  // false: check the image headers (sizes) only; `images` stays undefined
  bool progress = true;
};

// Reads a nerfstudio transforms.json (a path to the file, or the folder holding it) the way
// nerfstudio's NerfstudioDataParser does: frames sorted by file path, OPENCV intrinsics global or
// per frame, poses normalised over all frames (orientation, centring on the mean camera position,
// auto-scale) before the split. Every problem (a frame listed twice, missing, unreadable or cut
// short image, size ≠ intrinsics, NaN / non-rigid / implausibly far camera, empty train split) is
// reported with the frame index and file; all of them are collected first and then thrown as one
// neraf::Error.
ImageSet load_transforms_json(const std::string& path, const ImageLoadOptions& options = {});

// Same checks, without throwing: appends the problems to `problems` and returns what could be
// read. Every image is also decoded (and dropped), so that what the pixel loader would refuse is
// found here; `images` stays undefined.
ImageSet check_transforms_json(const std::string& path, const ImageLoadOptions& options,
                               ProblemList& problems);

// Maps dataset-frame points into the normalised frame: scale · (R p + t).
torch::Tensor to_normalized_world(const ImageSet& set, const torch::Tensor& points);  // [N,3] f64

}  // namespace neraf::data
