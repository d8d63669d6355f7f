#include "neraf/render/view.h"

#include <torch/torch.h>

#include <chrono>
#include <cmath>
#include <set>
#include <string>

#include "neraf/infer/image_output.h"
#include "neraf/io/json_file.h"
#include "neraf/nerf/render_image.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace neraf::render {

torch::Tensor colorize_depth(const torch::Tensor& depth, double near, double far) {
  const torch::Tensor d = depth.to(torch::kFloat32);
  if (!(near < far)) {
    const torch::Tensor flat = d.reshape({-1});
    near = torch::quantile(flat, 0.01).item<double>();
    far = torch::quantile(flat, 0.99).item<double>();
    if (!(far > near)) far = near + 1e-6;
  }
  return infer::viridis((d - near) / (far - near));
}

torch::Tensor normalize_pose(const torch::Tensor& c2w, const torch::Tensor& world_transform,
                             double world_scale) {
  const torch::Tensor m = c2w.to(torch::kFloat64);
  const torch::Tensor R = world_transform.to(torch::kFloat64).slice(1, 0, 3);
  const torch::Tensor t = world_transform.to(torch::kFloat64).select(1, 3);
  const torch::Tensor rot = torch::matmul(R, m.slice(1, 0, 3));
  const torch::Tensor pos = (torch::matmul(R, m.select(1, 3)) + t) * world_scale;
  return torch::cat({rot, pos.unsqueeze(1)}, 1).to(torch::kFloat32);
}

namespace {

torch::Tensor matrix_from_json(const nlohmann::json& j, const std::string& where) {
  require(j.is_array() && (j.size() == 3 || j.size() == 4),
          where + ": expected a 4×4 or 3×4 matrix (array of rows)");
  std::vector<double> v;
  for (const auto& row : j) {
    require(row.is_array() && row.size() == 4, where + ": every row needs 4 numbers");
    for (const auto& x : row) {
      require(x.is_number(), where + ": matrix entries must be numbers");
      v.push_back(x.get<double>());
      require(std::isfinite(v.back()), where + ": matrix entries must be finite");
    }
  }
  torch::Tensor m = torch::tensor(v, torch::kFloat64).view({static_cast<int64_t>(j.size()), 4});
  if (j.size() == 4) {
    const auto last = m[3];
    require(torch::allclose(last, torch::tensor({0.0, 0.0, 0.0, 1.0}, torch::kFloat64), 1e-6, 1e-6),
            where + ": the last row of a 4×4 pose must be 0 0 0 1");
    m = m.slice(0, 0, 3);
  }
  const torch::Tensor R = m.slice(1, 0, 3);
  const double ortho =
      (torch::matmul(R, R.t()) - torch::eye(3, torch::kFloat64)).abs().max().item<double>();
  require(ortho < 1e-3, where +
                            ": the rotation part is not orthonormal (a camera-to-world "
                            "matrix is [R | t] with R a rotation)");
  // A reflection (determinant -1) is orthonormal too, but no camera; transforms.json refuses both.
  require(torch::det(R).item<double>() > 0,
          where +
              ": the rotation part is a reflection (determinant -1); write a rotation with "
              "determinant +1");
  require(m.slice(1, 3, 4).abs().max().item<double>() <= 10000,
          where + ": the camera position is implausible (a coordinate beyond ±10000 m)");
  return m;
}

}  // namespace

Camera dataset_camera(const torch::Tensor& c2w, const nlohmann::json& manifest) {
  Camera cam;
  std::vector<double> wt;
  for (const auto& row : manifest.at("world_transform"))
    for (const auto& x : row) wt.push_back(x.get<double>());
  cam.c2w = normalize_pose(c2w, torch::tensor(wt, torch::kFloat64).view({3, 4}),
                           manifest.at("world_scale").get<double>());
  cam.intrinsics = infer::manifest_intrinsics(manifest, -1);
  return cam;
}

torch::Tensor listener_camera_to_world(const geometry::Vec3& position, double heading_deg) {
  // R_y(θ) maps the camera's forward −z to (−sin θ, 0, −cos θ): −z at 0°, −x at 90°.
  const double th = heading_deg * M_PI / 180.0, c = std::cos(th), s = std::sin(th);
  return torch::tensor({c, 0.0, s, position.x, 0.0, 1.0, 0.0, position.y, -s, 0.0, c, position.z},
                       torch::kFloat64)
      .view({3, 4});
}

Camera read_camera_file(const std::string& path, const nlohmann::json& manifest) {
  const nlohmann::json j = io::read_json(path);
  nlohmann::json m;
  if (j.is_array()) {
    m = j;
  } else {
    require(j.is_object(), path + ": expected an object with \"camera_to_world\" or a matrix");
    if (j.contains("camera_to_world"))
      m = j["camera_to_world"];
    else if (j.contains("transform_matrix"))
      m = j["transform_matrix"];
    else
      throw Error(path + ": missing \"camera_to_world\" (a 4×4 or 3×4 camera-to-world matrix)");
  }
  // A misspelt key would otherwise be ignored and the default camera rendered without a word.
  auto known_keys = [&](const nlohmann::json& object, const std::set<std::string>& known,
                        const std::string& what) {
    for (auto it = object.begin(); it != object.end(); ++it) {
      std::string list;
      for (const std::string& key : known) list += (list.empty() ? "" : ", ") + key;
      require(known.count(it.key()) > 0, path + ": " + what + "unknown key " +
                                             json_quoted(it.key()) + "; the known keys are " +
                                             list);
    }
  };
  if (j.is_object()) known_keys(j, {"camera_to_world", "transform_matrix", "intrinsics"}, "");
  Camera cam = dataset_camera(matrix_from_json(m, path + ": camera_to_world"), manifest);
  if (j.is_object() && j.contains("intrinsics")) {
    nlohmann::json k = j["intrinsics"];
    require(k.is_object(), path + ": \"intrinsics\" must be an object");
    known_keys(k,
               {"fx", "fy", "cx", "cy", "width", "height", "k1", "k2", "k3", "p1", "p2", "fl_x",
                "fl_y", "w", "h"},
               "intrinsics: ");
    // Accept transforms.json spellings.
    for (auto [from, to] : {std::pair<const char*, const char*>{"fl_x", "fx"},
                            {"fl_y", "fy"},
                            {"w", "width"},
                            {"h", "height"}})
      if (k.contains(from) && !k.contains(to)) k[to] = k[from];
    // Missing fields keep the default camera's values (the principal point is not rescaled when
    // only the size changes: give cx, cy with a new width/height).
    // A new image size changes what the default focal length and principal point mean.
    const auto changes = [&](const char* key, int now) {
      return k.contains(key) && k[key].is_number_integer() && k[key] != now;
    };
    const bool resized = changes("width", cam.intrinsics.width) ||
                         changes("height", cam.intrinsics.height);
    for (const char* key : {"fx", "fy", "cx", "cy"})
      require(!resized || k.contains(key),
              path + ": intrinsics: give fx, fy, cx and cy with a new width or height (" + key +
                  " is missing; the dataset camera's are for " +
                  std::to_string(cam.intrinsics.width) + "x" +
                  std::to_string(cam.intrinsics.height) + ")");
    nlohmann::json merged = {{"fx", cam.intrinsics.fx},       {"fy", cam.intrinsics.fy},
                             {"cx", cam.intrinsics.cx},       {"cy", cam.intrinsics.cy},
                             {"width", cam.intrinsics.width}, {"height", cam.intrinsics.height}};
    for (auto it = k.begin(); it != k.end(); ++it) merged[it.key()] = it.value();
    cam.intrinsics = infer::intrinsics_from_json(merged, path + ": intrinsics");
    const auto& in = cam.intrinsics;
    require(in.cx >= 0 && in.cx <= in.width && in.cy >= 0 && in.cy <= in.height,
            path + ": intrinsics: the principal point (cx, cy) must lie inside the " +
                std::to_string(in.width) + "x" + std::to_string(in.height) + " image");
  }
  return cam;
}

ViewOutputs render_view(infer::LoadedRun& run, const Camera& camera, const std::string& png,
                        const std::string& depth_png, int64_t chunk) {
  const auto t0 = std::chrono::steady_clock::now();
  const nerf::RenderedImage img =
      nerf::render_image(run.model, camera.c2w, camera.intrinsics, chunk);
  ViewOutputs out;
  out.rgb = img.rgb.cpu();
  out.depth = img.depth.cpu();
  infer::write_png(png, out.rgb);
  if (!depth_png.empty()) infer::write_png(depth_png, colorize_depth(out.depth));
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace neraf::render
