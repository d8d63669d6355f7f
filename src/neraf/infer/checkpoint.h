#pragma once
// Checkpoint files: LibTorch archives sealed with a checksum (io/sealed_file.h, magic
// "NERAFCKP") and written durably and atomically (temporary file, fsync, rename), named
// RUN/checkpoints/step-XXXXXXXXX.pt (9-digit step, so names sort by step); the energy
// calibration fitted for one sits beside it as step-XXXXXXXXX.calibration.pt. The trainer writes
// them (train/trainer.h); reading them (the header check, modules) is here, for loading a run.
#include <torch/nn/module.h>
#include <torch/serialize/input-archive.h>
#include <torch/serialize/output-archive.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "neraf/infer/train_config.h"

namespace neraf::infer {

// The archive's "format" entry (archive layout: train/trainer.h, Trainer::save_checkpoint).
constexpr const char* kCheckpointFormat = "neraf-checkpoint-1";

std::string checkpoint_dir(const std::string& run_dir);                 // RUN/checkpoints
std::string checkpoint_path(const std::string& run_dir, int64_t step);  // .../step-000001000.pt
// The highest-step checkpoint in RUN/checkpoints, if any.
std::optional<std::string> latest_checkpoint(const std::string& run_dir);
// The checkpoint a command reads from the run: `checkpoint` (--checkpoint) when given, which must
// be one of RUN/checkpoints (another run's, even of the same config, would be read with this
// run's data and calibration, and calibrate would overwrite that run's calibration), else the
// latest. neraf::Error otherwise.
std::string checkpoint_of_run(const std::string& run_dir, const std::string& checkpoint);
// Every checkpoint in RUN/checkpoints, highest step first.
std::vector<std::string> checkpoints_newest_first(const std::string& run_dir);
// neraf::Error when RUN/checkpoints is something else than a folder, or holds an entry named as
// a checkpoint that is no regular file (a folder, a link to a device): such a run would read as
// "no checkpoint yet" and train over it.
void check_checkpoint_folder(const std::string& run_dir);
// Deletes all but the `keep` newest checkpoints (and their calibrations); keep ≤ 0 keeps all.
// Returns how many were deleted.
int prune_checkpoints(const std::string& run_dir, int keep);
// The calibration file of a checkpoint: step-XXXXXXXXX.calibration.pt beside it.
std::string calibration_path(const std::string& checkpoint);
// The step encoded in a checkpoint file name (−1 when the name does not follow the pattern).
int64_t checkpoint_step_from_name(const std::string& path);

// Writes `archive` to `path` atomically (the parent folder is created).
void save_archive(torch::serialize::OutputArchive& archive, const std::string& path);
// Reads an archive; a missing, truncated, foreign or damaged (checksum) file is a neraf::Error
// naming it. Unsealed archives (written before checksums) still load.
void load_archive(torch::serialize::InputArchive& archive, const std::string& path);
// The same from a checkpoint file's bytes (`path` names it in errors): what rank 0 of a
// distributed run read and broadcast.
void load_archive_bytes(torch::serialize::InputArchive& archive, const std::string& file,
                        const std::string& path);
// "" when the file's seal is intact, else why not (truncated, damaged, ...), without parsing
// the archive (resume falls back past damaged checkpoints with this).
std::string checkpoint_damage(const std::string& path);

// module.load(archive), plus what LibTorch does not check: every parameter and buffer keeps its
// shape (LibTorch would silently resize them). neraf::Error naming `where` on any mismatch.
void load_module(torch::nn::Module& module, torch::serialize::InputArchive& archive,
                 const std::string& where);

// Reads a checkpoint's header ("format" and the resolved config) and checks that it describes
// the same model as `config` (preset, modality, model settings except precision); neraf::Error
// naming `path` and the first differing setting otherwise. Returns the stored config JSON.
nlohmann::json check_checkpoint_header(torch::serialize::InputArchive& archive,
                                       const TrainConfig& config, const std::string& path);

// The one key of `a` and `b` (JSON objects) that differs first, as a dotted path ("" if equal).
std::string first_difference(const nlohmann::json& a, const nlohmann::json& b,
                             const std::string& prefix = "");

}  // namespace neraf::infer
