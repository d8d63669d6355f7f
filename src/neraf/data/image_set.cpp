#include "neraf/data/image_set.h"

#include <omp.h>
#include <stb/stb_image.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "neraf/data/transforms_json.h"
#include "neraf/io/atomic_file.h"
#include "neraf/io/json_file.h"
#include "neraf/io/png.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data {
namespace {

using detail::frame_name;
using detail::Transforms;
using detail::TransformsFrame;

using Mat3 = std::array<std::array<double, 3>, 3>;

// Rotation taking unit vector a onto unit vector b (Rodrigues), with nerfstudio's handling of
// (anti)parallel vectors: a fixed perpendicular axis is used.
Mat3 rotation_between(std::array<double, 3> a, std::array<double, 3> b) {
  auto normalise = [](std::array<double, 3>& v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (double& x : v) x /= n;
  };
  auto cross = [](const std::array<double, 3>& u, const std::array<double, 3>& v) {
    return std::array<double, 3>{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                 u[0] * v[1] - u[1] * v[0]};
  };
  normalise(a);
  normalise(b);
  std::array<double, 3> v = cross(a, b);
  if (std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2]) < 1e-6) {
    const std::array<double, 3> x =
        std::abs(a[0]) < 1e-6 ? std::array<double, 3>{1, 0, 0} : std::array<double, 3>{0, 1, 0};
    v = cross(a, x);
  }
  normalise(v);
  const double c = std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0, 1.0);
  const double theta = std::acos(c);
  const Mat3 k = {{{0, -v[2], v[1]}, {v[2], 0, -v[0]}, {-v[1], v[0], 0}}};
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double kk = 0;
      for (int m = 0; m < 3; ++m) kk += k[i][m] * k[m][j];
      r[i][j] = (i == j ? 1.0 : 0.0) + std::sin(theta) * k[i][j] + (1 - std::cos(theta)) * kk;
    }
  return r;
}

// Reads `path_in` (transforms.json or the folder holding it) and parses it (transforms_json.h).
Transforms parse(const std::string& path_in, const ImageLoadOptions& options,
                 ProblemList& problems) {
  Transforms out;
  std::error_code ec;
  out.json_path =
      fs::is_directory(path_in, ec) ? (fs::path(path_in) / "transforms.json").string() : path_in;
  out.data_dir = fs::path(out.json_path).parent_path().string();
  if (out.data_dir.empty()) out.data_dir = ".";
  if (!fs::exists(out.json_path, ec)) {
    problems.error(out.json_path, "no such file",
                   "point to a nerfstudio dataset folder holding transforms.json");
    return out;
  }
  std::string text;
  try {
    text = io::read_text_file(out.json_path);
  } catch (const Error& e) {
    problems.error("", e.what(), "");
    return out;
  }
  return detail::parse_transforms_json(text, out.json_path, out.data_dir, options.orientation,
                                       problems);
}

// Reads each image's header; records sizes and problems.
void check_images(Transforms& p, ProblemList& problems) {
  for (TransformsFrame& f : p.frames) {
    std::error_code ec;
    if (!fs::exists(f.path, ec)) {
      problems.error(p.json_path, frame_name(f) + ": image " + f.path + " does not exist",
                     "add the image or remove the frame from transforms.json");
      continue;
    }
    // stb_image accepts a file cut short and decodes its missing part as zeros.
    const std::string damage = io::image_file_problem(f.path);
    if (!damage.empty()) {
      problems.error(p.json_path,
                     frame_name(f) + ": image " + f.path + " is unusable (" + damage + ")",
                     "re-copy or re-export the image");
      continue;
    }
    int w = 0, h = 0, n = 0;
    if (!stbi_info(f.path.c_str(), &w, &h, &n)) {
      problems.error(p.json_path,
                     frame_name(f) + ": image " + f.path + " cannot be read (" +
                         (stbi_failure_reason() ? stbi_failure_reason() : "unknown format") + ")",
                     "convert it to PNG or JPEG");
      continue;
    }
    f.image_w = w;
    f.image_h = h;
    if (f.has_size && (w != f.intr.width || h != f.intr.height)) {
      problems.error(p.json_path,
                     frame_name(f) + ": image is " + std::to_string(w) + "x" + std::to_string(h) +
                         " but the intrinsics say " + std::to_string(f.intr.width) + "x" +
                         std::to_string(f.intr.height),
                     "fix w/h (and fl_x, fl_y, cx, cy) or resize the image");
      continue;
    }
    if (!f.has_size) {  // take the size from the image itself
      f.intr.width = w;
      f.intr.height = h;
    }
    f.image_ok = true;
  }
}

// Decodes every image that passed the header checks (in parallel, one image per thread in memory
// at a time), so that validation finds what the pixel loader would throw on.
void check_decodes(const Transforms& p, ProblemList& problems) {
  const int64_t n = static_cast<int64_t>(p.frames.size());
  std::vector<std::string> failures(static_cast<size_t>(n));
#pragma omp parallel for schedule(dynamic)
  for (int64_t k = 0; k < n; ++k) {
    const TransformsFrame& f = p.frames[k];
    if (!f.image_ok) continue;
    int w = 0, h = 0, c = 0;
    stbi_uc* px = stbi_load(f.path.c_str(), &w, &h, &c, 3);
    if (!px || w != f.image_w || h != f.image_h)
      failures[k] = frame_name(f) + ": image " + f.path + " cannot be decoded (" +
                    (px ? "its size changed" : "damaged image data") + ")";
    if (px) stbi_image_free(px);
  }
  for (const std::string& msg : failures)
    if (!msg.empty()) problems.error(p.json_path, msg, "re-export the image as PNG or JPEG");
}

ImageSet build(const std::string& path, const ImageLoadOptions& options, ProblemList& problems,
               bool decode, bool verify_pixels = false) {
  Transforms p = parse(path, options, problems);
  ImageSet set;
  set.source = p.json_path;
  set.world_transform = torch::zeros({3, 4}, torch::kFloat64);
  for (int i = 0; i < 3; ++i) set.world_transform[i][i] = 1.0;
  if (p.frames.empty()) return set;
  check_images(p, problems);

  std::vector<int64_t> train, eval;
  detail::split_transforms(p, options.eval_mode, options.train_fraction, problems, train, eval,
                           set.eval_mode);
  if (train.empty())
    problems.error(p.json_path, "the train split is empty (eval mode " + set.eval_mode + ")",
                   "add train frames (file names with train_ for the filename split)");
  if (eval.empty())
    problems.warning(p.json_path, "the eval split is empty (eval mode " + set.eval_mode + ")",
                     "image metrics will be skipped; add eval_ frames or more images");

  // TransformsFrame size consistency (the images tensor is [N, H, W, 3]).
  const TransformsFrame* first = nullptr;
  for (const TransformsFrame& f : p.frames) {
    if (!f.image_ok) continue;
    if (!first) {
      first = &f;
    } else if (f.image_w != first->image_w || f.image_h != first->image_h) {
      problems.error(p.json_path,
                     frame_name(f) + ": image is " + std::to_string(f.image_w) + "x" +
                         std::to_string(f.image_h) + " but " + frame_name(*first) + " is " +
                         std::to_string(first->image_w) + "x" + std::to_string(first->image_h),
                     "all images of a scene must have the same size; resize them");
    }
  }

  // Pose normalisation over all frames with a valid pose, before the split (as nerfstudio).
  std::vector<const TransformsFrame*> posed;
  for (const TransformsFrame& f : p.frames)
    if (f.pose_ok) posed.push_back(&f);
  Mat3 rot = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  std::array<double, 3> mean{0, 0, 0};
  if (!posed.empty()) {
    std::array<double, 3> up{0, 0, 0};
    for (const TransformsFrame* f : posed)
      for (int r = 0; r < 3; ++r) {
        mean[r] += f->pose[r][3] / posed.size();
        up[r] += f->pose[r][1] / posed.size();  // camera y axis = "up" in OpenGL cameras
      }
    if (p.orientation == "up") {
      const double un = std::sqrt(up[0] * up[0] + up[1] * up[1] + up[2] * up[2]);
      if (un > 1e-12) {
        rot = rotation_between(up, {0, 0, 1});
      } else {
        problems.warning(p.json_path, "the cameras' up vectors cancel out; orientation skipped",
                         "set \"orientation_override\": \"none\" to silence this");
      }
    }
  }
  std::array<double, 3> t{};
  for (int r = 0; r < 3; ++r)
    t[r] = -(rot[r][0] * mean[0] + rot[r][1] * mean[1] + rot[r][2] * mean[2]);
  // Oriented poses: [rot·Rc | rot·tc + t].
  std::vector<std::array<double, 12>> oriented(p.frames.size());
  double max_abs_t = 0;
  for (size_t i = 0; i < p.frames.size(); ++i) {
    const TransformsFrame& f = p.frames[i];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        double v = 0;
        for (int k = 0; k < 3; ++k) v += rot[r][k] * f.pose[k][c];
        if (c == 3) v += t[r];
        oriented[i][r * 4 + c] = v;
      }
    if (f.pose_ok)
      for (int r = 0; r < 3; ++r) max_abs_t = std::max(max_abs_t, std::abs(oriented[i][r * 4 + 3]));
  }
  double scale = 1.0;
  if (options.auto_scale) {
    if (max_abs_t > 0) {
      scale = 1.0 / max_abs_t;
    } else if (posed.size() > 1) {
      problems.warning(p.json_path, "all cameras are at the same position; scale left at 1",
                       "check the transform_matrix translations");
    }
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) set.world_transform[r][c] = rot[r][c];
    set.world_transform[r][3] = t[r];
  }
  set.world_scale = scale;

  auto fill = [&](ImageSplit& split, const std::vector<int64_t>& idx, bool is_train) {
    const int64_t n = static_cast<int64_t>(idx.size());
    split.camera_to_world = torch::zeros({n, 3, 4}, torch::kFloat32);
    auto acc = split.camera_to_world.accessor<float, 3>();
    for (int64_t k = 0; k < n; ++k) {
      const TransformsFrame& f = p.frames[idx[k]];
      split.files.push_back(f.path);
      split.intrinsics.push_back(f.intr);
      split.appearance_ids.push_back(is_train ? k : -1);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c)
          acc[k][r][c] = static_cast<float>(oriented[idx[k]][r * 4 + c] * (c == 3 ? scale : 1.0));
    }
  };
  fill(set.train, train, true);
  fill(set.eval, eval, false);

  if (!decode) {
    if (verify_pixels) check_decodes(p, problems);
    return set;
  }
  if (problems.num_errors() > 0 || !first) return set;

  const int H = first->image_h, W = first->image_w;
  ProgressOptions popt;
  popt.unit = "img";
  popt.enabled = options.progress;
  Progress progress("loading images", static_cast<int64_t>(p.frames.size()), popt);
  std::atomic<int64_t> done{0};
  for (ImageSplit* split : {&set.train, &set.eval}) {
    const int64_t n = split->size();
    split->images = torch::empty({n, H, W, 3}, torch::kUInt8);
    uint8_t* base = split->images.data_ptr<uint8_t>();
    std::vector<std::string> failures(n);
#pragma omp parallel for schedule(dynamic)
    for (int64_t k = 0; k < n; ++k) {
      int w = 0, h = 0, c = 0;
      stbi_uc* px = stbi_load(split->files[k].c_str(), &w, &h, &c, 3);
      if (!px || w != W || h != H) {
        failures[k] = split->files[k] + ": cannot be decoded (" +
                      (stbi_failure_reason() ? stbi_failure_reason() : "size changed") +
                      "); re-export the image as PNG or JPEG";
      } else {
        std::memcpy(base + k * int64_t(H) * W * 3, px, size_t(H) * W * 3);
      }
      if (px) stbi_image_free(px);
      const int64_t d = ++done;
      if (omp_get_thread_num() == 0) progress.update(d);  // Progress is not thread-safe
    }
    for (const std::string& msg : failures)
      if (!msg.empty()) throw Error(msg);
  }
  progress.finish();
  return set;
}

}  // namespace

ImageSet check_transforms_json(const std::string& path, const ImageLoadOptions& options,
                               ProblemList& problems) {
  return build(path, options, problems, /*decode=*/false, /*verify_pixels=*/true);
}

ImageSet load_transforms_json(const std::string& path, const ImageLoadOptions& options) {
  ProblemList problems;
  ImageSet set = build(path, options, problems, options.load_pixels);
  problems.throw_if_errors(fs::path(set.source).parent_path().string());
  problems.print_warnings();
  return set;
}

torch::Tensor to_normalized_world(const ImageSet& set, const torch::Tensor& points) {
  TORCH_CHECK(points.dim() == 2 && points.size(1) == 3, "points must be [N, 3]");
  const torch::Tensor p = points.to(torch::kFloat64);
  const torch::Tensor r =
      set.world_transform.index({torch::indexing::Slice(), torch::indexing::Slice(0, 3)});
  const torch::Tensor t = set.world_transform.index({torch::indexing::Slice(), 3});
  return (p.matmul(r.t()) + t) * set.world_scale;
}

}  // namespace neraf::data
