#pragma once
// Posed images of one scene (the vision half of a dataset), as the radiance field consumes them.
// Poses are camera-to-world in the nerfstudio/OpenGL convention (x right, y up, camera looks
// along −z), already normalised by `world_transform` (nerfstudio dataparser: orientation,
// centring on the poses, auto-scale so that max |t| = 1).
#include <torch/torch.h>

#include <string>
#include <vector>

namespace neraf::data {

struct Intrinsics {  // OPENCV camera model, pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;  // distortion (zero for the simulator)
};

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
  std::string source;             // the transforms.json it was read from
};

}  // namespace neraf::data
