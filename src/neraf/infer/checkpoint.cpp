#include "neraf/infer/checkpoint.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "neraf/io/atomic_file.h"
#include "neraf/io/sealed_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::infer {

namespace {
bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}
}  // namespace

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
  const std::vector<std::string> all = checkpoints_newest_first(run_dir);
  if (all.empty()) return std::nullopt;
  return all.front();
}

std::string checkpoint_of_run(const std::string& run_dir, const std::string& checkpoint) {
  std::error_code ec;
  if (checkpoint.empty()) {
    check_checkpoint_folder(run_dir);
    const auto latest = latest_checkpoint(run_dir);
    if (!latest) {
      // A checkpoint renamed by hand is not listed: say so rather than "train first".
      for (const auto& entry : fs::directory_iterator(checkpoint_dir(run_dir), ec)) {
        const std::string name = entry.path().filename().string();
        require(name.rfind("step-", 0) != 0 || !ends_with(name, ".pt") ||
                    ends_with(name, ".calibration.pt"),
                entry.path().string() +
                    ": not named as neraf names checkpoints (step-NNNNNNNNN.pt, 9 digits), so "
                    "it is not used; rename it to its step or remove it");
      }
      throw Error(run_dir + ": no checkpoint yet; train first (neraf train --out " + run_dir + ")");
    }
    return *latest;
  }
  const fs::path parent = fs::absolute(checkpoint, ec).parent_path();
  require(fs::exists(checkpoint, ec),
          "--checkpoint " + checkpoint + ": no such file; pick one of " + checkpoint_dir(run_dir));
  require(fs::is_regular_file(checkpoint, ec),
          "--checkpoint " + checkpoint +
              ": is not a regular file (a folder, FIFO or device); pick "
              "one of " +
              checkpoint_dir(run_dir));
  require(!ends_with(checkpoint, ".calibration.pt"),
          "--checkpoint " + checkpoint +
              ": is a calibration file; give the checkpoint beside it (the same name without "
              "\".calibration\")");
  require(checkpoint_step_from_name(checkpoint) >= 0,
          "--checkpoint " + checkpoint +
              ": not named as neraf names checkpoints (step-NNNNNNNNN.pt); pick one of " +
              checkpoint_dir(run_dir));
  require(fs::equivalent(parent, checkpoint_dir(run_dir), ec),
          "--checkpoint " + checkpoint + ": not a checkpoint of the run " + run_dir +
              " (it must be in " + checkpoint_dir(run_dir) +
              "); pass that checkpoint's own run with --run");
  return checkpoint;
}

namespace {
constexpr const char* kSealMagic = "NERAFCKP";
constexpr uint32_t kSealVersion = 1;
std::string first_line(const std::string& s) { return s.substr(0, s.find('\n')); }
}  // namespace

void save_archive(torch::serialize::OutputArchive& archive, const std::string& path) {
  // Serialised in memory and written by neraf (not LibTorch's writer, whose errors, e.g. a full
  // disk, escape as std::terminate), sealed with a checksum so that changed bytes are detected.
  std::ostringstream payload;
  try {
    archive.save_to(payload);
  } catch (const std::exception& e) {
    throw Error(path + ": cannot serialise the checkpoint (" + first_line(e.what()) + ")");
  }
  io::write_text_atomically(path, io::seal(kSealMagic, kSealVersion, payload.str()));
}

std::string checkpoint_damage(const std::string& path) {
  try {
    const std::string file = io::read_text_file(path);
    if (io::has_magic(file, "PK\x03\x04")) return "";  // unsealed (before seals): cannot tell
    io::unseal(file, kSealMagic, kSealVersion, path);
    return "";
  } catch (const Error& e) {
    return e.what();
  }
}

void load_archive(torch::serialize::InputArchive& archive, const std::string& path) {
  std::error_code ec;
  require(fs::is_regular_file(path, ec), path + ": no such checkpoint file; check the run folder");
  load_archive_bytes(archive, io::read_text_file(path), path);
}

void load_archive_bytes(torch::serialize::InputArchive& archive, const std::string& file,
                        const std::string& path) {
  // A damaged calibration file is fitted again; a damaged checkpoint is skipped on resume.
  const std::string fix = ends_with(path, ".calibration.pt")
                              ? "; delete it and run neraf calibrate --run " +
                                    fs::path(path).parent_path().parent_path().string()
                              : "; delete it to resume from the previous checkpoint";
  try {
    if (io::has_magic(file,
                      "PK\x03\x04")) {  // a zip archive: written before checkpoints were sealed
      archive.load_from(file.data(), file.size());
      return;
    }
    require(io::has_magic(file, kSealMagic),
            path +
                ": not a neraf checkpoint (unknown format); point at a file written by "
                "neraf train");
    const io::Unsealed sealed = io::unseal(file, kSealMagic, kSealVersion, path);
    archive.load_from(sealed.payload.data(), sealed.payload.size());
  } catch (const Error& e) {
    throw Error(e.what() + fix);
  } catch (const std::exception&) {
    throw Error(path + ": not a readable neraf checkpoint (truncated or corrupted)" + fix);
  }
}

void check_checkpoint_folder(const std::string& run_dir) {
  const std::string dir = checkpoint_dir(run_dir);
  std::error_code ec;
  require(!fs::exists(dir, ec) || fs::is_directory(dir, ec),
          dir +
              ": is not a folder, so the run's checkpoints are gone; restore the folder or "
              "train again in a new --out");
  for (const auto& entry : fs::directory_iterator(dir, ec))
    require(checkpoint_step_from_name(entry.path().string()) < 0 || entry.is_regular_file(ec),
            entry.path().string() +
                ": named as a checkpoint but not a regular file (a folder, or a link to one or "
                "to a device); remove it or restore the checkpoint");
}

std::vector<std::string> checkpoints_newest_first(const std::string& run_dir) {
  std::vector<std::pair<int64_t, std::string>> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(checkpoint_dir(run_dir), ec)) {
    if (!entry.is_regular_file()) continue;
    const int64_t s = checkpoint_step_from_name(entry.path().string());
    if (s >= 0) found.emplace_back(s, entry.path().string());
  }
  std::sort(found.rbegin(), found.rend());
  std::vector<std::string> out;
  for (auto& f : found) out.push_back(std::move(f.second));
  return out;
}

std::string calibration_path(const std::string& checkpoint) {
  const fs::path p(checkpoint);
  return (p.parent_path() / (p.stem().string() + ".calibration.pt")).string();
}

int prune_checkpoints(const std::string& run_dir, int keep) {
  if (keep <= 0) return 0;
  const std::vector<std::string> all = checkpoints_newest_first(run_dir);
  int removed = 0;
  std::error_code ec;
  for (size_t i = static_cast<size_t>(keep); i < all.size(); ++i) {
    fs::remove(calibration_path(all[i]), ec);
    if (fs::remove(all[i], ec)) ++removed;
  }
  return removed;
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
  for (const char* k : {"steps", "steps_from_data", "threads", "save_every", "eval_rays_per_chunk"})
    j.erase(k);
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
    // A checkpoint copied in from another run under another step's name would load as this
    // run's (found by probing: the same config and dataset pass every other check).
    torch::Tensor step;
    a.read("step", step);
    const int64_t named = checkpoint_step_from_name(path);
    require(named < 0 || (step.numel() == 1 && step.item<int64_t>() == named),
            path + ": holds step " + std::to_string(step.numel() == 1 ? step.item<int64_t>() : -1) +
                ", not the step its name says (copied from another run?); use the run's own "
                "checkpoints");
  } catch (const c10::Error&) {
    throw Error(path + ": checkpoint header is unreadable (corrupted file); delete it");
  } catch (const nlohmann::json::exception&) {
    throw Error(path + ": checkpoint config is corrupted; delete the file");
  }
  const nlohmann::json mine = to_json(config);
  if (stored.value("preset", "") != config.preset)
    throw Error(path + ": checkpoint was trained with --preset " + stored.value("preset", "?") +
                ", this run uses --preset " + config.preset +
                "; it belongs to another run folder (to train another preset, start a new run)");
  // Keys newer than the checkpoint take their preset defaults, as when config.json is read.
  const nlohmann::json stored_full = to_json(train_config_from_json(stored, path));
  const std::string diff = first_difference(comparable(stored_full), comparable(mine));
  if (!diff.empty())
    throw Error(path + ": checkpoint was trained with a different config (" + diff +
                " differs); it belongs to another run folder, or the run's config.json was edited");
  return stored;
}

}  // namespace neraf::infer
