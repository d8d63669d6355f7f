// `neraf info DIR`: what a dataset folder holds (layout, counts, sample rate, durations, pose
// boxes, T60 distribution) and every problem the loaders would stumble on, each with its file,
// what is wrong and how to fix it. The checks are the loaders' own (data/validate.h), so no
// error here means `neraf train` accepts the data. Exit 1 when there is any error (warnings
// alone exit 0).
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/data/validate.h"
#include "neraf/metrics/room_acoustics.h"
#include "neraf/util/error.h"

namespace neraf::cli {
namespace {

struct InfoArgs {
  std::string dir;
  int64_t max_problems = 50;
  int64_t t60_sample = 2000;
  bool no_t60 = false;
  bool json = false;
};

nlohmann::json stats_json(const data::Stats& s) {
  if (s.count == 0) return nullptr;
  return {
      {"count", s.count}, {"min", s.min}, {"mean", s.mean}, {"median", s.median}, {"max", s.max}};
}

nlohmann::json box_json(const data::Aabb& b) {
  return {{"min", {b.min.x, b.min.y, b.min.z}}, {"max", {b.max.x, b.max.y, b.max.z}}};
}

nlohmann::json report_json(const data::DatasetReport& r) {
  nlohmann::json j = {{"dataset", r.dir},
                      {"layout",
                       {{"soundspaces", r.layout.soundspaces},
                        {"raf", r.layout.raf},
                        {"nerfstudio", r.layout.nerfstudio},
                        {"simulated", r.layout.simulated}}}};
  if (r.layout.has_audio()) {
    j["audio"] = {{"layout", data::to_string(r.audio_layout)},
                  {"rirs_train", r.rirs_train},
                  {"rirs_test", r.rirs_test},
                  {"sample_rate", r.expected_sample_rate},
                  {"channels", r.expected_channels},
                  {"magnitude_files", r.magnitude_files},
                  {"duration_s", stats_json(r.duration_s)},
                  {"mic_box", box_json(r.mic_box)},
                  {"source_box", box_json(r.source_box)},
                  {"audio_aabb", box_json(r.audio_aabb)},
                  {"test_mics_outside_aabb", r.test_mics_outside},
                  {"sources_outside_aabb", r.sources_outside},
                  {"t60_s", stats_json(r.t60_s)},
                  {"t60_rirs", r.t60_rirs},
                  {"t60_invalid_channels", r.t60_invalid},
                  {"t60_subsampled", r.t60_subsampled}};
  }
  if (r.layout.nerfstudio)
    j["images"] = {{"train", r.images_train},
                   {"eval", r.images_eval},
                   {"width", r.image_width},
                   {"height", r.image_height},
                   {"split", r.image_eval_mode}};
  nlohmann::json problems = nlohmann::json::array();
  for (const data::Problem& p : r.problems)
    problems.push_back({{"severity", p.is_error() ? "error" : "warning"},
                        {"file", p.file},
                        {"what", p.what},
                        {"fix", p.fix}});
  j["problems"] = problems;
  return j;
}

void run(const InfoArgs& args) {
  data::InspectOptions options;
  options.max_sample_reads = args.t60_sample;
  options.progress = !args.json;
  if (!args.no_t60) {
    options.t60 = [](const io::AudioBuffer& rir, data::AudioLayout layout) {
      const metrics::Variant v =
          layout == data::AudioLayout::raf ? metrics::Variant::raf : metrics::Variant::soundspaces;
      std::vector<double> out;
      for (const auto& ch : rir.channels) {
        const metrics::DecayTime t = metrics::measure_t60(ch, rir.sample_rate, v);
        out.push_back(t.valid() ? t.seconds : std::nan(""));
      }
      return out;
    };
  }
  // As train --data, the folder or its transforms.json.
  std::error_code ec;
  std::string dir = args.dir;
  if (!std::filesystem::is_directory(dir, ec)) {
    require(std::filesystem::path(dir).filename() == "transforms.json",
            dir + ": is a file; give the dataset folder (or its transforms.json)");
    dir = std::filesystem::path(dir).parent_path().string();
    if (dir.empty()) dir = ".";
  }
  const data::DatasetReport report = data::inspect_dataset(dir, options);

  if (args.json) {
    std::printf("%s\n", report_json(report).dump(2).c_str());
  } else {
    std::printf("%s", data::format_report(report).c_str());
    int64_t shown = 0;
    const int64_t limit = args.max_problems > 0 ? args.max_problems : INT64_MAX;
    // Errors first, then warnings, each in the order found.
    for (const bool errors : {true, false})
      for (const data::Problem& p : report.problems) {
        if (p.is_error() != errors) continue;
        if (shown++ < limit)
          std::fprintf(stderr, "%s: %s\n", errors ? "error" : "warning", p.to_string().c_str());
      }
    if (shown > limit)
      std::fprintf(stderr, "... and %lld more (pass --max-problems 0 to list them all)\n",
                   static_cast<long long>(shown - limit));
  }
  const int64_t n = report.num_errors();
  if (n > 0)
    throw Error(args.dir + ": " + std::to_string(n) + " error(s) found (listed above); fix them " +
                "before training");
}

}  // namespace

void register_info(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "info",
      "Inspect and validate a dataset folder: detects the layout (SoundSpaces, RAF, nerfstudio "
      "images, simulated scene), checks every file training reads with the loaders' own checks "
      "(split entries; poses; every RIR and magnitude file in full: truncation, sample rate, "
      "channels, NaN or huge samples, length; every image: truncation, decoding, size vs "
      "intrinsics, duplicates) and prints a summary (counts, durations, mic/source boxes, audio "
      "aabb, T60). Exits 1 if any error is found: no error means training accepts the data.");
  cmd->add_option("dir", args->dir,
                  "Dataset folder (a SoundSpaces scene, a RAF room, or a "
                  "nerfstudio folder with transforms.json), or its transforms.json")
      ->required()
      ->check(CLI::ExistingPath);
  cmd->add_option("--max-problems", args->max_problems,
                  "Print at most this many problems (0 = all)")
      ->capture_default_str()
      ->transform(whole_number(0, 10000000));
  cmd->add_option("--t60-sample", args->t60_sample,
                  "Measure T60 on at most this many RIRs (an evenly spaced subset on larger "
                  "datasets; the checks read every file)")
      ->capture_default_str()
      ->transform(whole_number(1, 100000000));
  cmd->add_flag("--no-t60", args->no_t60, "Skip the T60 summary");
  cmd->add_flag("--json", args->json,
                "Print the summary and the problem list as JSON on stdout instead of text");
  cmd->callback([args] { run(*args); });
}

}  // namespace neraf::cli
