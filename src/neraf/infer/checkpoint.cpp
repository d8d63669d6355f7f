#include "neraf/infer/checkpoint.h"

#include <cstdio>
#include <filesystem>

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::infer {

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
      throw Error(path +
                  ": cannot write the checkpoint (disk full or not writable?); free space "
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
    throw Error(path +
                ": not a readable neraf checkpoint (truncated or corrupted); delete it to "
                "resume from the previous checkpoint");
  }
}

void load_module(torch::nn::Module& module, torch::serialize::InputArchive& archive,
                 const std::string& where) {
  std::vector<std::pair<std::string, std::vector<int64_t>>> shapes;
  for (const auto& p : module.named_parameters())
    shapes.emplace_back(p.key(), p.value().sizes().vec());
  for (const auto& b : module.named_buffers())
    shapes.emplace_back(b.key(), b.value().sizes().vec());
  try {
    module.load(archive);
  } catch (const c10::Error& e) {
    std::string what = e.what_without_backtrace();
    throw Error(where + ": checkpoint does not match this model (" +
                what.substr(0, what.find('\n')) +
                "); it was written for another config or dataset");
  }
  const auto params = module.named_parameters();
  const auto buffers = module.named_buffers();
  for (const auto& [name, shape] : shapes) {
    const torch::Tensor* t = params.find(name);
    if (!t) t = buffers.find(name);
    if (!t || t->sizes().vec() != shape)
      throw Error(
          where + ": checkpoint tensor '" + name + "' has another shape than this model's " +
          "(another dataset or config?); use the dataset and config the run was trained with");
  }
}

namespace {

// Settings that may differ between a checkpoint and the run loading it: run length and
// bookkeeping, and the matmul precision (the master weights are fp32 either way). A schedule
// whose decay is tied to the run length (max_steps == steps) follows --steps on resume, so it
// compares as "the run length", not as a number.
nlohmann::json comparable(nlohmann::json j) {
  const nlohmann::json steps = j.value("steps", nlohmann::json());
  for (nlohmann::json* s : {&j["fields"], &j["proposal_networks"], &j["audio"]["schedule"]})
    if (s->is_object() && s->value("max_steps", nlohmann::json()) == steps)
      (*s)["max_steps"] = "steps";
  for (const char* k : {"steps", "threads", "save_every", "eval_rays_per_chunk"}) j.erase(k);
  if (j.contains("model")) j["model"].erase("precision");
  // Vision runs ignore the acoustic settings (and checkpoints older than them have none).
  if (j.value("modality", "") == "vision") j.erase("audio");
  return j;
}
}  // namespace

std::string first_difference(const nlohmann::json& a, const nlohmann::json& b,
                             const std::string& prefix) {
  if (a.is_object() && b.is_object()) {
    for (auto it = a.begin(); it != a.end(); ++it) {
      const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
      if (!b.contains(it.key())) return key;
      const std::string d = first_difference(it.value(), b[it.key()], key);
      if (!d.empty()) return d;
    }
    for (auto it = b.begin(); it != b.end(); ++it)
      if (!a.contains(it.key())) return prefix.empty() ? it.key() : prefix + "." + it.key();
    return "";
  }
  if (a.is_array() && b.is_array() && a.size() == b.size()) {
    for (size_t i = 0; i < a.size(); ++i) {
      const std::string d = first_difference(a[i], b[i], prefix + "[" + std::to_string(i) + "]");
      if (!d.empty()) return d;
    }
    return "";
  }
  return a == b ? "" : (prefix.empty() ? "(root)" : prefix);
}

nlohmann::json check_checkpoint_header(torch::serialize::InputArchive& a, const TrainConfig& config,
                                       const std::string& path) {
  nlohmann::json stored;
  try {
    c10::IValue fmt;
    require(
        a.try_read("format", fmt) && fmt.isString() && fmt.toStringRef() == kCheckpointFormat,
        path + ": not a neraf training checkpoint; point --run at a folder made by neraf train");
    c10::IValue cfg;
    a.read("config", cfg);
    stored = nlohmann::json::parse(cfg.toStringRef());
  } catch (const c10::Error&) {
    throw Error(path + ": checkpoint header is unreadable (corrupted file); delete it");
  } catch (const nlohmann::json::exception&) {
    throw Error(path + ": checkpoint config is corrupted; delete the file");
  }
  const nlohmann::json mine = to_json(config);
  if (stored.value("preset", "") != config.preset)
    throw Error(path + ": checkpoint was trained with --preset " + stored.value("preset", "?") +
                ", this run uses --preset " + config.preset +
                "; use the same preset or a new --out folder");
  // Keys newer than the checkpoint take their preset defaults, as when config.json is read.
  const nlohmann::json stored_full = to_json(train_config_from_json(stored, path));
  const std::string diff = first_difference(comparable(stored_full), comparable(mine));
  if (!diff.empty())
    throw Error(path + ": checkpoint was trained with a different config (" + diff +
                " differs); use the run's own config.json or a new --out folder");
  return stored;
}

}  // namespace neraf::infer
