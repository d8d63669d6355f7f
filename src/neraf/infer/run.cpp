#include "neraf/infer/run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string_view>

#include "neraf/infer/checkpoint.h"
#include "neraf/io/json_file.h"
#include "neraf/io/sealed_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::infer {

namespace {
constexpr const char* kManifestFormat = "neraf-run-data-1";
}  // namespace

namespace {

nlohmann::json matrix_json(const torch::Tensor& m) {  // [3, 4]
  const torch::Tensor c = m.to(torch::kFloat64).contiguous();
  nlohmann::json rows = nlohmann::json::array();
  for (int64_t r = 0; r < c.size(0); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int64_t k = 0; k < c.size(1); ++k) row.push_back(c[r][k].item<double>());
    rows.push_back(row);
  }
  return rows;
}

std::string run_file(const std::string& run_dir, const char* name) {
  return (fs::path(run_dir) / name).string();
}

}  // namespace

nlohmann::json make_data_manifest(const data::ImageSet& images, const std::string& data_dir) {
  std::error_code ec;
  const std::string abs = fs::absolute(data_dir, ec).lexically_normal().string();
  nlohmann::json eval_poses = nlohmann::json::array(), eval_intr = nlohmann::json::array();
  for (int64_t i = 0; i < images.eval.size(); ++i) {
    eval_poses.push_back(matrix_json(images.eval.camera_to_world[i]));
    eval_intr.push_back(intrinsics_json(images.eval.intrinsics[static_cast<size_t>(i)]));
  }
  const data::Intrinsics& k0 = images.train.intrinsics.at(0);
  // Image paths relative to the dataset folder, so the same data read from another working
  // directory (or by absolute path) matches.
  const fs::path root = fs::path(images.source).parent_path();
  // The training pictures' pixels, hashed: two rooms with the same image names and poses (two
  // synth runs of different scenes) still differ here.
  const auto pixel_hash = [](const torch::Tensor& images) {
    const torch::Tensor pixels = images.contiguous();
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx",
                  static_cast<unsigned long long>(io::fnv1a64(std::string_view(
                      static_cast<const char*>(pixels.data_ptr()), pixels.nbytes()))));
    return std::string(hex);
  };
  auto relative = [&root](const std::vector<std::string>& files) {
    std::vector<std::string> out;
    for (const auto& f : files) out.push_back(fs::path(f).lexically_relative(root).string());
    return out;
  };
  return {{"format", kManifestFormat},
          {"data", abs},
          {"source", images.source},
          {"eval_mode", images.eval_mode},
          {"num_train", images.train.size()},
          {"num_eval", images.eval.size()},
          {"height", k0.height},
          {"width", k0.width},
          {"train_files", relative(images.train.files)},
          {"train_pixels_fnv1a", pixel_hash(images.train.images)},
          {"eval_pixels_fnv1a", pixel_hash(images.eval.images)},
          {"eval_files", relative(images.eval.files)},
          {"world_transform", matrix_json(images.world_transform)},
          {"world_scale", images.world_scale},
          {"default_intrinsics", intrinsics_json(k0)},
          {"eval_intrinsics", eval_intr},
          {"eval_camera_to_world", eval_poses}};
}

namespace {

acoustic::WorldToField world_to_field(const torch::Tensor& transform, double scale) {
  const torch::Tensor m = (transform.to(torch::kFloat64) * scale).contiguous();  // [3, 4]
  acoustic::WorldToField out{};
  std::copy(m.data_ptr<double>(), m.data_ptr<double>() + 12, out.begin());
  return out;
}

}  // namespace

acoustic::WorldToField world_to_field(const data::ImageSet& images) {
  return world_to_field(images.world_transform, images.world_scale);
}

acoustic::WorldToField world_to_field(const nlohmann::json& manifest, const std::string& where) {
  const nlohmann::json rows = manifest.value("world_transform", nlohmann::json());
  const nlohmann::json scale = manifest.value("world_scale", nlohmann::json());
  bool ok = rows.is_array() && rows.size() == 3 && scale.is_number();
  acoustic::WorldToField out{};
  for (size_t r = 0; ok && r < 3; ++r) {
    ok = rows[r].is_array() && rows[r].size() == 4;
    for (size_t k = 0; ok && k < 4; ++k) {
      ok = rows[r][k].is_number() && std::isfinite(rows[r][k].get<double>());
      if (ok) out[4 * r + k] = rows[r][k].get<double>() * scale.get<double>();
    }
  }
  require(ok && std::isfinite(scale.get<double>()),
          where +
              ": its world_transform / world_scale are missing or damaged; re-run neraf "
              "train (the acoustic field reads the grid through them)");
  return out;
}

void check_vision_run_data(const std::string& vision_run, const nlohmann::json& now) {
  const std::string path = run_file(vision_run, "data.json");
  std::error_code ec;
  require(fs::is_regular_file(path, ec),
          vision_run +
              ": not a training run (no data.json); point --vision-run at a neraf train "
              "--out folder");
  const nlohmann::json was = io::read_json(path);
  require(was.is_object() && was.value("format", "") == kManifestFormat,
          path + ": not a neraf run data manifest; re-run neraf train");
  const std::string their = was.value("data", std::string("?"));
  const std::string ours = now.value("data", std::string("?"));
  auto refuse = [&](const std::string& what) {
    throw Error(vision_run + ": trained on " + their + ", not on --data " + ours + " (its " + what +
                " differ); pass the vision run trained on this dataset");
  };
  for (const char* key : {"num_train", "width", "height", "train_files"})
    if (was.value(key, nlohmann::json()) != now.value(key, nlohmann::json())) refuse(key);
  // The normalisation (cameras' mean, orientation, scale) is computed from the poses: two rooms
  // with the same image names and sizes still differ here. Compared with a tolerance, as JSON
  // round trips doubles only to their printed digits.
  auto close = [](const nlohmann::json& a, const nlohmann::json& b) {
    if (!a.is_number() || !b.is_number()) return false;
    const double x = a.get<double>(), y = b.get<double>();
    return std::abs(x - y) <= 1e-9 * std::max({1.0, std::abs(x), std::abs(y)});
  };
  const nlohmann::json& ws = was.value("world_scale", nlohmann::json());
  if (!close(ws, now.value("world_scale", nlohmann::json()))) refuse("world_scale");
  const nlohmann::json a = was.value("world_transform", nlohmann::json());
  const nlohmann::json b = now.value("world_transform", nlohmann::json());
  bool same = a.is_array() && b.is_array() && a.size() == b.size();
  for (size_t r = 0; same && r < a.size(); ++r) {
    same = a[r].is_array() && b[r].is_array() && a[r].size() == b[r].size();
    for (size_t c = 0; same && c < a[r].size(); ++c) same = close(a[r][c], b[r][c]);
  }
  if (!same) refuse("camera poses (world_transform)");
  // Runs from before the pixel hash have none; then the checks above are all there is.
  if (was.contains("train_pixels_fnv1a") && was["train_pixels_fnv1a"] != now["train_pixels_fnv1a"])
    refuse("training pictures (train_pixels_fnv1a)");
}

torch::Tensor manifest_eval_poses(const nlohmann::json& m) {
  const auto& poses = m.at("eval_camera_to_world");
  std::vector<double> flat;
  for (const auto& p : poses)
    for (const auto& row : p)
      for (const auto& v : row) flat.push_back(v.get<double>());
  return torch::tensor(flat, torch::kFloat64)
      .view({static_cast<int64_t>(poses.size()), 3, 4})
      .to(torch::kFloat32);
}

data::Intrinsics manifest_intrinsics(const nlohmann::json& m, int64_t eval_index) {
  if (eval_index < 0) return intrinsics_from_json(m.at("default_intrinsics"), "data.json");
  return intrinsics_from_json(m.at("eval_intrinsics").at(static_cast<size_t>(eval_index)),
                              "data.json");
}

int64_t scene_flag(const std::string& run_dir, const std::string& selector,
                   const std::string& flag) {
  if (selector.empty()) return -1;
  const std::string path = run_file(run_dir, "data.json");
  std::error_code ec;
  require(
      fs::is_regular_file(path, ec),
      run_dir + ": not a training run (no data.json); point --run at a neraf train --out folder");
  return find_scene(io::read_json(path), selector, run_dir, flag);
}

std::string scene_key(const std::string& key, int64_t scene) {
  return scene == 0 ? key : key + "_" + std::to_string(scene);
}

std::vector<std::string> name_scenes(const std::vector<std::string>& data_dirs) {
  std::vector<std::string> names;
  for (const std::string& d : data_dirs) {
    fs::path p = fs::path(d).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();
    if (p.filename() == "transforms.json") p = p.parent_path();
    names.push_back(p.filename().string());
  }
  for (size_t i = 0; i < names.size(); ++i) {
    bool unique = !names[i].empty();
    for (size_t j = 0; j < names.size(); ++j) unique = unique && (i == j || names[i] != names[j]);
    if (!unique) names[i] = "scene" + std::to_string(i);
  }
  return names;
}

std::vector<std::string> run_input_folders(const std::string& run_dir) {
  std::vector<std::string> folders;
  auto read = [&](const char* name) {
    try {
      return io::read_json(run_file(run_dir, name));
    } catch (const std::exception&) {
      return nlohmann::json();
    }
  };
  auto add = [&](const nlohmann::json& j, const char* key) {
    if (j.is_object() && j.contains(key) && j[key].is_string())
      folders.push_back(j[key].get<std::string>());
  };
  const nlohmann::json manifest = read("data.json");
  add(manifest, "data");
  if (is_multiscene(manifest))
    for (const nlohmann::json& scene : manifest["scenes"]) add(scene, "data");
  const nlohmann::json config = read("config.json");
  if (config.is_object() && config.contains("audio")) {
    add(config["audio"], "vision_run");
    if (config["audio"].contains("vision_runs") && config["audio"]["vision_runs"].is_array())
      for (const nlohmann::json& v : config["audio"]["vision_runs"])
        if (v.is_string()) folders.push_back(v.get<std::string>());
  }
  return folders;
}

std::string run_config_file(const std::string& run_dir) {
  std::error_code ec;
  const fs::file_status folder = fs::status(run_dir, ec);
  require(fs::exists(folder), run_dir + ": no such run folder; check --run");
  require(fs::is_directory(folder), run_dir + ": is a file, not a run folder; " +
                                        (fs::path(run_dir).extension() == ".nrf"
                                             ? "an exported model goes to --model"
                                             : "point --run at a neraf train --out folder"));
  const std::string config_path = run_file(run_dir, "config.json");
  const bool found = fs::is_regular_file(config_path, ec);
  require(ec != std::errc::permission_denied,
          run_dir +
              ": may not be read (permission denied); run as the run's owner or give "
              "yourself read access to the folder");
  require(found, run_dir +
                     ": not a training run (no config.json); point --run at a neraf train --out "
                     "folder");
  return config_path;
}

LoadedRun load_run(const std::string& run_dir, torch::Device device,
                   const std::string& checkpoint) {
  const std::string config_path = run_config_file(run_dir);
  const std::string manifest_path = run_file(run_dir, "data.json");
  LoadedRun run;
  run.run_dir = run_dir;
  run.config = read_run_config(config_path);
  run.manifest = io::read_json(manifest_path);
  check_data_paths(run.manifest, manifest_path);
  require(!is_multiscene(run.manifest),
          run_dir +
              ": a multi-scene acoustic run has no radiance field of its own; use its "
              "scenes' vision runs (audio.vision_runs in its config.json)");
  require(run.manifest.is_object() && run.manifest.value("format", "") == kManifestFormat &&
              run.manifest.contains("num_train"),
          manifest_path + ": not a neraf run data manifest; re-run neraf train");
  run.checkpoint = checkpoint_of_run(run_dir, checkpoint);
  if (run.config.model.precision == nerf::Precision::bf16 && !nerf::cpu_supports_bf16())
    run.config.model.precision = nerf::Precision::fp32;  // same weights, no slow bf16 emulation
  run.model = nerf::NerfactoModel(run.config.model, run.manifest["num_train"].get<int64_t>(),
                                  run.config.seed);
  torch::serialize::InputArchive a;
  load_archive(a, run.checkpoint);
  check_checkpoint_header(a, run.config, run.checkpoint);
  try {
    torch::serialize::InputArchive branch, model;
    a.read("branch_vision", branch);
    branch.read("model", model);
    load_module(*run.model, model, run.checkpoint);
    torch::Tensor step;
    a.read("step", step);
    run.step = step.item<int64_t>();
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    throw Error(run.checkpoint + ": checkpoint does not match the run's config (" +
                what.substr(0, what.find('\n')) + "); it belongs to another run");
  }
  run.model->to(device);
  run.model->eval();
  return run;
}

}  // namespace neraf::infer
