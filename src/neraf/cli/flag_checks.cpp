#include "neraf/cli/flag_checks.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

#include "neraf/infer/run.h"
#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"
#include "neraf/util/number_text.h"

namespace fs = std::filesystem;

namespace neraf::cli {

CLI::Validator whole_number(int64_t lo, int64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) {
        std::string canonical;
        std::string why = check_integer(text, lo, hi, &canonical);
        if (why.empty()) text = canonical;  // CLI11 converts only plain decimal
        return why;
      },
      range_text(lo, hi));
}

CLI::Validator seed_number(uint64_t hi) {
  return CLI::Validator(
      [hi](std::string& text) {
        std::string canonical;
        std::string why = check_unsigned(text, hi, &canonical);
        if (why.empty()) text = canonical;
        return why;
      },
      "[0, " + std::to_string(hi) + "]");
}

CLI::Validator real_number(double lo, double hi, bool lo_open) {
  return CLI::Validator(
      [lo, hi, lo_open](std::string& text) { return check_real(text, lo, hi, lo_open); },
      range_text(lo, hi, lo_open));
}

CLI::Validator thread_count() {
  const int most = max_thread_count();
  return CLI::Validator(
      [most](std::string& text) {
        std::string canonical;
        std::string why = check_integer(text, 1, most, &canonical);
        if (!why.empty())
          return why + " (at most 4 x the " + std::to_string(most / 4) +
                 " hardware threads of this machine)";
        text = canonical;
        return why;
      },
      range_text(int64_t{1}, int64_t{most}));
}

namespace {
bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  return fs::weakly_canonical(a, ec) == fs::weakly_canonical(b, ec);
}

// `path` is `folder` or lies inside it, both resolved through the links that exist.
bool inside(const std::string& path, const std::string& folder) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  const fs::path f = fs::weakly_canonical(fs::absolute(folder, ec), ec);
  if (ec || f.empty()) return false;
  const fs::path rel = p.lexically_relative(f);
  return !rel.empty() && *rel.begin() != "..";
}

// The folders the output `out` may not be written into: input folders (--data, --novel-data),
// the run's datasets and vision runs (unless `out` is in the run folder, which may lie inside
// its dataset), its checkpoints folder.
std::vector<FlagPath> protected_folders(const std::string& out, const std::vector<FlagPath>& inputs,
                                        const std::string& run_dir) {
  std::vector<FlagPath> folders;
  std::error_code ec;
  for (const FlagPath& in : inputs)
    if (!in.path.empty() && fs::is_directory(in.path, ec)) folders.push_back(in);
  if (run_dir.empty()) return folders;
  if (!inside(out, run_dir))
    for (const std::string& f : infer::run_input_folders(run_dir))
      folders.push_back({"a folder the run was made from (RUN/data.json, RUN/config.json)", f});
  folders.push_back({"the run's checkpoints folder", (fs::path(run_dir) / "checkpoints").string()});
  return folders;
}

void require_outside(const FlagPath& out, const std::vector<FlagPath>& folders) {
  for (const FlagPath& f : folders)
    require(!inside(out.path, f.path),
            out.flag + " " + out.path + ": is inside " + f.path + " (" + f.flag +
                "); writing there would change what neraf reads, so choose a path outside it");
}

void require_named(const FlagPath& out) {
  require(out.path != "-", out.flag + " -: neraf writes files, not standard output; give a path");
}
}  // namespace

void require_safe_output(const FlagPath& out, const std::vector<FlagPath>& inputs,
                         const std::string& run_dir) {
  if (out.path.empty()) return;
  require_named(out);
  require(out.path.back() != '/',
          out.flag + " " + out.path + ": ends in '/', so it names a folder; give a file name");
  io::require_replaceable_file(out.path);
  io::require_creatable(out.path);
  for (const FlagPath& in : inputs)
    require(in.path.empty() || !same_file(out.path, in.path),
            out.flag + " " + out.path + ": is also " + in.flag +
                "; writing it would destroy that file, so choose another output path");
  require_outside(out, protected_folders(out.path, inputs, run_dir));
  if (run_dir.empty()) return;
  const fs::path run(run_dir);
  for (const char* name : {"config.json", "data.json", ".lock"})
    require(!same_file(out.path, (run / name).string()),
            out.flag + " " + out.path + ": is the run's own " + name +
                "; choose an output path outside the run's files");
}

void require_safe_output_folder(const FlagPath& out, const std::vector<FlagPath>& inputs,
                                const std::string& run_dir) {
  if (out.path.empty()) return;
  require_named(out);
  std::error_code ec;
  require(!fs::exists(out.path, ec) || fs::is_directory(out.path, ec),
          out.flag + " " + out.path + ": exists and is not a folder; give a new or empty folder");
  io::require_creatable(out.path);
  for (const FlagPath& in : inputs)
    require(in.path.empty() || fs::is_directory(in.path, ec) || !inside(in.path, out.path),
            out.flag + " " + out.path + ": holds " + in.flag + " " + in.path +
                "; choose another output folder");
  require_outside(out, protected_folders(out.path, inputs, run_dir));
}

void require_cache_folder(const FlagPath& cache, const std::string& run_dir) {
  if (cache.path.empty() || run_dir.empty()) return;
  const std::string checkpoints = (fs::path(run_dir) / "checkpoints").string();
  require(!inside(cache.path, checkpoints),
          cache.flag + " " + cache.path + ": is inside " + checkpoints +
              " (the run's checkpoints folder); choose a cache folder outside it");
}

void require_extension(const FlagPath& out, const std::string& extension) {
  std::string ext = fs::path(out.path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext != extension)
    throw CLI::ValidationError(out.flag + " " + out.path + ": neraf writes this output as " +
                               extension + "; name it with that extension");
}

}  // namespace neraf::cli
