#pragma once
// A training run folder:
//   RUN/config.json                   the resolved TrainConfig (what --resume, render and eval use)
//   RUN/data.json                     data manifest: dataset path, frames, image size, the world
//                                     normalisation and the eval cameras (render needs no dataset)
//   RUN/checkpoints/step-*.pt         atomic checkpoints (periodic, final, and on Ctrl-C)
// train/run_training.h drives a Trainer over such a folder; load_run() gives render/eval the
// model, and the manifest helpers read the eval cameras back.
#include <torch/torch.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/acoustic/local_geometry.h"
#include "neraf/data/image_set.h"
#include "neraf/infer/run_manifest.h"
#include "neraf/infer/train_config.h"
#include "neraf/nerf/nerfacto_model.h"

namespace neraf::infer {

// The data manifest written to RUN/data.json.
nlohmann::json make_data_manifest(const data::ImageSet& images, const std::string& data_dir);

// neraf::Error naming `vision_run` when its RUN/data.json describes another dataset than
// `data_manifest` (make_data_manifest of --data): other train images (names, count, size) or
// another world normalisation. A frozen radiance field only describes the room it was trained
// on; an audio run on another room's grid trains without complaint and learns nothing useful.
void check_vision_run_data(const std::string& vision_run, const nlohmann::json& data_manifest);

// Multi-scene runs: is_multiscene, scene_names and find_scene (run_manifest.h).
// `--scene` of a command on RUN: −1 when `selector` is empty, else find_scene on RUN/data.json.
int64_t scene_flag(const std::string& run_dir, const std::string& selector,
                   const std::string& flag = "--scene");
// Checkpoint key of scene s: `key` for scene 0 (as a one-scene run writes it), else key_s.
std::string scene_key(const std::string& key, int64_t scene);
// Names for scenes from their dataset folders: the folder's name, unless two share it.
std::vector<std::string> name_scenes(const std::vector<std::string>& data_dirs);

// The folders a run was made from, which no command on the run may write into: its datasets
// (RUN/data.json "data", each scene's) and the vision runs its acoustic field stands on
// (config.json audio.vision_run / vision_runs). Best effort: a missing or damaged file adds
// nothing (loading the run reports it).
std::vector<std::string> run_input_folders(const std::string& run_dir);

// RUN_DIR/config.json, or neraf::Error saying why RUN_DIR is not a readable run (no such folder, a
// file (an exported model belongs to --model), a folder it may not read, no config.json).
std::string run_config_file(const std::string& run_dir);

// A trained run, ready for rendering (model in eval mode on `device`).
struct LoadedRun {
  std::string run_dir;
  TrainConfig config;
  nlohmann::json manifest;  // RUN/data.json
  std::string checkpoint;
  int64_t step = 0;
  nerf::NerfactoModel model{nullptr};
};
// Latest checkpoint of RUN (or `checkpoint` if given). neraf::Error when RUN is not a run folder,
// has no checkpoint, or the checkpoint is corrupted / from another config.
LoadedRun load_run(const std::string& run_dir, torch::Device device = torch::kCPU,
                   const std::string& checkpoint = "");

// The map from the dataset's metres into the radiance field's normalised frame (the RIR positions
// into the grid, acoustic/local_geometry.h): scale · (R p + t) of the images' normalisation,
// from an ImageSet or a (one-scene) run data manifest ("world_transform", "world_scale"; a
// manifest without them is named by `where`).
acoustic::WorldToField world_to_field(const data::ImageSet& images);
acoustic::WorldToField world_to_field(const nlohmann::json& manifest, const std::string& where);

// The eval cameras stored in the manifest: c2w [N, 3, 4] (normalised frame) and intrinsics.
torch::Tensor manifest_eval_poses(const nlohmann::json& manifest);
// eval_index −1: the default camera (first training frame).
data::Intrinsics manifest_intrinsics(const nlohmann::json& manifest, int64_t eval_index);
// intrinsics_from_json / intrinsics_json: run_manifest.h.

}  // namespace neraf::infer
