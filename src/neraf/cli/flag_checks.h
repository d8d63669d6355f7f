#pragma once
// Checked ranges for the numeric flags of every subcommand (neraf/util/number_text.h does the
// parsing): a value outside the range, a negative seed, NaN, 1e23 for an integer or any text that
// is not a number is a usage error naming the flag and the range ("--steps: must be a whole number
// in [1, 100000000]; got 99999999999999999999"), never a wrapped or clamped value. The range shows
// in --help after the type ("INT:[1, 100000000]").
#include <CLI/CLI.hpp>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace neraf::cli {

// Integer flags. Accepts "1e6" for 1000000 (it is handed on in plain decimal, so attach these
// three with ->transform(): CLI11's ->check() gives a validator a copy of the text).
CLI::Validator whole_number(int64_t lo, int64_t hi);
// Seeds: any unsigned 64-bit value, written as a whole number.
CLI::Validator seed_number(uint64_t hi = std::numeric_limits<uint64_t>::max());
// Real flags: finite and in [lo, hi] ((lo, hi] when lo_open).
CLI::Validator real_number(double lo, double hi, bool lo_open = false);
// --threads: [1, max_thread_count()] (4 x the machine's hardware threads).
CLI::Validator thread_count();

// A path a command was given, with the flag that gave it.
struct FlagPath {
  std::string flag, path;
};

// Before any work: neraf::Error unless the output file `out` is a path that may be written (a
// file name, not "-" or "dir/"; absent or a regular file, io::require_replaceable_file), names
// none of `inputs` (nor another output), lies in no input folder, and is no file of the run
// folder `run_dir` ("" for none): its config.json, data.json, lock, checkpoints, datasets or
// vision runs (infer::run_input_folders). Outputs replacing their own inputs destroyed a user's
// recording, model, dataset or run. An empty `out` (flag not given) passes.
void require_safe_output(const FlagPath& out, const std::vector<FlagPath>& inputs,
                         const std::string& run_dir = "");
// The same for an output folder (eval --images, render rir --poses --out, --frames): a folder or
// nothing yet, holding none of the input files, inside none of the protected folders.
void require_safe_output_folder(const FlagPath& out, const std::vector<FlagPath>& inputs,
                                const std::string& run_dir = "");

// --cache-dir: any folder but one inside the run's checkpoints folder (whose files retention and
// resume manage). An empty path (flag not given) passes.
void require_cache_folder(const FlagPath& cache, const std::string& run_dir);

// Usage error unless `path` ends in `extension` (".png", ".nrf"), case-insensitively: an output
// named for another format would hold bytes its name does not promise.
void require_extension(const FlagPath& out, const std::string& extension);

// Most steps a training run may be asked for (the paper preset runs 400001).
constexpr int64_t kMaxSteps = 100000000;

}  // namespace neraf::cli
