#include "neraf/cli/flag_checks.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

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
}  // namespace

void require_safe_output(const FlagPath& out, const std::vector<FlagPath>& inputs,
                         const std::string& run_dir) {
  if (out.path.empty()) return;
  io::require_replaceable_file(out.path);
  io::require_creatable(out.path);
  for (const FlagPath& in : inputs)
    require(in.path.empty() || !same_file(out.path, in.path),
            out.flag + " " + out.path + ": is also " + in.flag +
                "; writing it would destroy that file, so choose another output path");
  if (run_dir.empty()) return;
  const fs::path run(run_dir);
  for (const char* name : {"config.json", "data.json", ".lock"})
    require(!same_file(out.path, (run / name).string()),
            out.flag + " " + out.path + ": is the run's own " + name +
                "; choose an output path outside the run's files");
  std::error_code ec;
  const fs::path parent = fs::absolute(out.path, ec).parent_path();
  require(!same_file(parent.string(), (run / "checkpoints").string()),
          out.flag + " " + out.path +
              ": is in the run's checkpoints folder; choose an output path outside it");
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
