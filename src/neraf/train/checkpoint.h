#pragma once
// Checkpoint files: LibTorch archives written atomically (temporary file + rename), named
// RUN/checkpoints/step-XXXXXXXXX.pt (9-digit step, so names sort by step).
#include <torch/serialize/input-archive.h>
#include <torch/serialize/output-archive.h>

#include <torch/nn/module.h>

#include <cstdint>
#include <optional>
#include <string>

namespace neraf::train {

std::string checkpoint_dir(const std::string& run_dir);                  // RUN/checkpoints
std::string checkpoint_path(const std::string& run_dir, int64_t step);   // .../step-000001000.pt
// The highest-step checkpoint in RUN/checkpoints, if any.
std::optional<std::string> latest_checkpoint(const std::string& run_dir);
// The step encoded in a checkpoint file name (−1 when the name does not follow the pattern).
int64_t checkpoint_step_from_name(const std::string& path);

// Writes `archive` to `path` atomically (the parent folder is created).
void save_archive(torch::serialize::OutputArchive& archive, const std::string& path);
// Reads an archive; a missing, truncated or corrupted file is a neraf::Error naming it.
void load_archive(torch::serialize::InputArchive& archive, const std::string& path);

// module.load(archive), plus what LibTorch does not check: every parameter and buffer keeps its
// shape (LibTorch would silently resize them). neraf::Error naming `where` on any mismatch.
void load_module(torch::nn::Module& module, torch::serialize::InputArchive& archive,
                 const std::string& where);

}  // namespace neraf::train
