#pragma once
// Dataset inspection and validation (`neraf info DIR`): detects the layout, checks every file the
// loaders would read, and summarises what is there. Returns the problems as a list instead of
// throwing, so callers decide what to do (the CLI prints them and exits non-zero on errors).
//
// What is checked is what the loaders reject, through the same functions (rir_check.h,
// image_set.h), so "0 errors" means training accepts the data: split files and point/pose files
// (malformed entries, duplicate ids, entries without files, NaN, infinite or implausible
// (|x| > 10 km) positions or quaternions), every RIR file read in full (unreadable, truncated,
// wrong sample rate or channel count, longer than 30 s, NaN / infinite / huge samples; empty or
// all-zero → warning), SoundSpaces magnitude files (shape, NaN / negative / huge values), the
// feature cache the automatic max_len would make (one outlier RIR padding it many times over),
// images (listed twice, absent, cut short, undecodable, size ≠ intrinsics, non-rigid, NaN or
// implausible camera matrices, empty split). The T60 summary runs on an evenly spaced subset when
// there are more than InspectOptions::max_sample_reads RIRs.
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "neraf/data/layout.h"
#include "neraf/data/problem.h"
#include "neraf/data/rir_set.h"
#include "neraf/io/audio_file.h"

namespace neraf::data {

struct Stats {
  int64_t count = 0;
  double min = std::numeric_limits<double>::quiet_NaN();
  double mean = std::numeric_limits<double>::quiet_NaN();
  double median = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
};
Stats compute_stats(std::vector<double> values);  // NaNs are skipped (not counted)

struct InspectOptions {
  // Per-channel T60 (s) of one RIR; NaN where it has no value. Empty: no T60 summary. The CLI
  // passes the metrics stage's reference T60 (data does not depend on metrics).
  std::function<std::vector<double>(const io::AudioBuffer& rir, AudioLayout layout)> t60;
  int64_t max_sample_reads = 2000;  // RIRs whose samples are read for T60 (evenly spaced subset)
  bool check_images = true;
  bool progress = true;
};

struct DatasetReport {
  std::string dir;
  DatasetLayout layout;

  // Audio (when layout.has_audio()).
  AudioLayout audio_layout = AudioLayout::soundspaces;
  int64_t rirs_train = 0, rirs_test = 0;
  int64_t magnitude_files = 0;    // SoundSpaces .npy files found for the split's RIRs
  int expected_sample_rate = 0;   // what the layout requires (44100 / 48000)
  int expected_channels = 0;      // 2 / 1
  Stats duration_s;               // over every readable RIR (from the headers)
  Aabb mic_box, source_box;       // all RIRs
  Aabb audio_aabb;                // train mics ± 1 m
  int64_t test_mics_outside = 0;  // test mics the position normalisation zeroes
  int64_t sources_outside = 0;    // sources (all RIRs) outside the audio aabb -> zeroed
  Stats t60_s;                    // per channel, valid values only
  int64_t t60_rirs = 0;           // RIRs measured
  int64_t t60_invalid = 0;        // channels without a T60 value
  bool t60_subsampled = false;    // true when t60_rirs < number of RIRs

  // Images (when layout.nerfstudio).
  int64_t images_train = 0, images_eval = 0;
  int image_width = 0, image_height = 0;
  std::string image_eval_mode;

  std::vector<Problem> problems;
  int64_t num_errors() const;
  int64_t num_warnings() const;
};

DatasetReport inspect_dataset(const std::string& dir, const InspectOptions& options = {});

// inspect_dataset(dir).problems without the T60 summary.
std::vector<Problem> validate_dataset(const std::string& dir);

// The human-readable summary `neraf info` prints (no problem list).
std::string format_report(const DatasetReport& report);

}  // namespace neraf::data
