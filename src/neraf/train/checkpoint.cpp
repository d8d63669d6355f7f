#include "neraf/train/checkpoint.h"

#include <cstdio>
#include <filesystem>

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::train {

std::string checkpoint_dir(const std::string& run_dir) {
  return (fs::path(run_dir) / "checkpoints").string();
}

std::string checkpoint_path(const std::string& run_dir, int64_t step) {
  char name[64];
  std::snprintf(name, sizeof name, "step-%09lld.pt", static_cast<long long>(step));
  return (fs::path(checkpoint_dir(run_dir)) / name).string();
}

int64_t checkpoint_step_from_name(const std::string& path) {
  const std::string name = fs::path(path).filename().string();
  long long step = -1;
  char tail[8] = {0};
  if (name.size() != 17 || std::sscanf(name.c_str(), "step-%9lld%4s", &step, tail) != 2 ||
      std::string(tail) != ".pt")
    return -1;
  return step;
}

std::optional<std::string> latest_checkpoint(const std::string& run_dir) {
  std::error_code ec;
  const fs::path dir = checkpoint_dir(run_dir);
  if (!fs::is_directory(dir, ec)) return std::nullopt;
  int64_t best = -1;
  std::string best_path;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    const int64_t s = checkpoint_step_from_name(entry.path().string());
    if (s > best) {
      best = s;
      best_path = entry.path().string();
    }
  }
  if (best < 0) return std::nullopt;
  return best_path;
}

void save_archive(torch::serialize::OutputArchive& archive, const std::string& path) {
  io::write_atomically(path, [&](const std::string& tmp) {
    try {
      archive.save_to(tmp);
    } catch (const c10::Error& e) {
      throw Error(path + ": cannot write the checkpoint (disk full or not writable?); free space "
                         "or choose another --out");
    }
  });
}

void load_archive(torch::serialize::InputArchive& archive, const std::string& path) {
  std::error_code ec;
  require(fs::is_regular_file(path, ec), path + ": no such checkpoint file; check the run folder");
  try {
    archive.load_from(path);
  } catch (const c10::Error&) {
    throw Error(path + ": not a readable neraf checkpoint (truncated or corrupted); delete it to "
                       "resume from the previous checkpoint");
  }
}

void load_module(torch::nn::Module& module, torch::serialize::InputArchive& archive,
                 const std::string& where) {
  std::vector<std::pair<std::string, std::vector<int64_t>>> shapes;
  for (const auto& p : module.named_parameters()) shapes.emplace_back(p.key(), p.value().sizes().vec());
  for (const auto& b : module.named_buffers()) shapes.emplace_back(b.key(), b.value().sizes().vec());
  try {
    module.load(archive);
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    throw Error(where + ": checkpoint does not match this model (" + what.substr(0, what.find('\n')) +
                "); it was written for another config or dataset");
  }
  const auto params = module.named_parameters();
  const auto buffers = module.named_buffers();
  for (const auto& [name, shape] : shapes) {
    const torch::Tensor* t = params.find(name);
    if (!t) t = buffers.find(name);
    if (!t || t->sizes().vec() != shape)
      throw Error(where + ": checkpoint tensor '" + name + "' has another shape than this model's " +
                  "(another dataset or config?); use the dataset and config the run was trained with");
  }
}

}  // namespace neraf::train
