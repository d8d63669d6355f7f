#pragma once
// Rendering views of a trained radiance field to PNG files.
#include <torch/types.h>

#include <nlohmann/json.hpp>
#include <string>

#include "neraf/data/image_set.h"
#include "neraf/geometry/vec.h"
#include "neraf/infer/run.h"

namespace neraf::render {

// Depth → colour: depth normalised between `near` and `far` (when near ≥ far: the 1st and 99th
// percentiles of the image), then the viridis ramp (near = dark purple).
// depth: [H, W] → [H, W, 3] float in [0, 1].
torch::Tensor colorize_depth(const torch::Tensor& depth, double near = 0, double far = 0);

struct Camera {
  torch::Tensor c2w;  // [3, 4] float32, normalised (model) frame
  data::Intrinsics intrinsics;
};

// A camera from a JSON file in the dataset's own frame (as in transforms.json):
//   {"camera_to_world": 4×4 or 3×4}   (also accepted: "transform_matrix", or the bare matrix)
//   optional "intrinsics": {"fx","fy","cx","cy","width","height"[, "k1","k2","k3","p1","p2"]}
//   (transforms.json spellings fl_x, fl_y, w, h are accepted too). Missing intrinsics default to
// the run's first training camera. The pose is mapped with the run's world normalisation
// (R_n = R·R_c, t_n = scale·(R·t_c + t)). Errors name the file.
Camera read_camera_file(const std::string& path, const nlohmann::json& manifest);

// A camera at a dataset-frame camera-to-world [3, 4] float64 with the run's first training
// camera's intrinsics (manifest: the run's RUN/data.json).
Camera dataset_camera(const torch::Tensor& c2w, const nlohmann::json& manifest);

// The dataset-frame camera-to-world [3, 4] float64 of a listener at `position` (metres, y up)
// facing the audio heading `heading_deg` (a rotation about +y: 0° looks along −z, 90° along −x,
// as SoundSpaces' receiver headings), camera looking along its −z with +y up (nerfstudio).
torch::Tensor listener_camera_to_world(const geometry::Vec3& position, double heading_deg);

// Maps a dataset-frame camera-to-world [3, 4] into the normalised frame.
torch::Tensor normalize_pose(const torch::Tensor& c2w, const torch::Tensor& world_transform,
                             double world_scale);

struct ViewOutputs {
  torch::Tensor rgb;    // [H, W, 3]
  torch::Tensor depth;  // [H, W]
  double seconds = 0;
};

// Renders `camera` with the run's model; writes rgb to `png` and, if `depth_png` is not empty,
// the colour-mapped median depth there (atomic writes).
ViewOutputs render_view(infer::LoadedRun& run, const Camera& camera, const std::string& png,
                        const std::string& depth_png = "", int64_t chunk = 16384);

}  // namespace neraf::render
