// RAF (Real Acoustic Fields) in the layout the published NeRAF code reads (neraf-reference.md
// §3.3):
//   <room>/metadata/data-split.json  {"train": [[ids]], "validation": [[...]], "test": [[ids]]}
//   <room>/data/<id>/rir.wav         mono, 48 kHz
//   <room>/data/<id>/rx_pos.txt      "x,y,z"              microphone (omni), m
//   <room>/data/<id>/tx_pos.txt      "qx,qy,qz,qw,x,y,z"  source orientation (real last), position
// The split and pose files are parsed by pose_files.h; this file checks the files they name.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>

#include "neraf/data/audio_probe.h"
#include "neraf/data/pose_files.h"
#include "neraf/data/rir_check.h"
#include "neraf/data/rir_layouts.h"
#include "neraf/dsp/stft.h"
#include "neraf/geometry/quaternion.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data::detail {
namespace {

static_assert(kMaxAbsPoseCoordinate == kMaxAbsCoordinate,
              "pose_files.h and rir_check.h bound positions alike");

// Python's round(): halves go to the even neighbour (std::nearbyint in the default mode).
int round_half_even(double v) { return static_cast<int>(std::nearbyint(v)); }

std::vector<float> read_mono48k(const std::string& wav, ProblemList& problems) {
  const AudioProbe p = probe_audio(wav);
  require(p.ok, wav + ": " + p.error);
  require(p.sample_rate == kRafRate,
          wav + ": sample rate " + std::to_string(p.sample_rate) +
              " Hz, RAF RIRs must be 48000 Hz (the published code supports only 48 kHz); "
              "resample the file to 48 kHz");
  require(p.channels == 1, wav + ": " + std::to_string(p.channels) +
                               " channels, RAF RIRs must be mono; keep one channel");
  if (p.frames == 0) return {};
  io::AudioBuffer a = io::read_audio(wav);
  check_rir_samples(wav, a.channels, problems);
  return std::move(a.channels[0]);
}

}  // namespace

RirIndex index_raf(const std::string& dir, ProblemList& problems) {
  RirIndex idx;
  RirSet& set = idx.set;
  set.layout = AudioLayout::raf;
  set.root = dir;
  set.wav_sample_rate = kRafRate;
  set.sample_rate = kRafRate;
  set.channels = 1;
  set.stft = dsp::StftParams::raf();
  set.n_freq = set.stft.n_freq();

  const std::string split_path = (fs::path(dir) / "metadata/data-split.json").string();
  std::error_code ec;
  if (!fs::exists(split_path, ec)) {
    problems.error(split_path, "missing",
                   "copy data-split/<room>.json of the RAF repository to metadata/data-split.json");
    return idx;
  }
  json split;
  try {
    split = io::read_json(split_path);
  } catch (const Error& e) {
    problems.error("", e.what(), "");
    return idx;
  }
  const std::array<const json*, 2> lists = raf_split_lists(split, split_path, problems);
  if (!lists[0]) return idx;

  std::set<std::string> seen;
  const char* names[2] = {"train", "test"};
  for (int li = 0; li < 2; ++li) {
    const json& list = *lists[li];
    for (size_t k = 0; k < list.size(); ++k) {
      const std::string where = std::string(names[li]) + "[0][" + std::to_string(k) + "]";
      const std::optional<std::string> given = raf_split_id(list[k], where, split_path, problems);
      if (!given) continue;
      std::string id = *given;
      std::string folder = (fs::path(dir) / "data" / id).string();
      if (!fs::is_directory(folder, ec) && list[k].is_string()) {
        // "123" written without the zero padding of the folder names
        const std::optional<std::string> padded = raf_padded_id(id);
        if (padded && fs::is_directory(fs::path(dir) / "data" / *padded, ec)) {
          id = *padded;
          folder = (fs::path(dir) / "data" / id).string();
        }
      }
      if (!seen.insert(id).second) {
        problems.error(split_path,
                       where + " " + json_quoted(id) + " is listed twice (duplicate id)",
                       "remove the duplicate id");
        continue;
      }
      if (!fs::is_directory(folder, ec)) {
        problems.error(folder, "split entry " + where + " " + json_quoted(id) + " has no folder",
                       "restore data/" + id + " or remove the id from " + split_path);
        continue;
      }
      Rir rir;
      rir.id = id;
      rir.wav_path = (fs::path(folder) / "rir.wav").string();
      const FileStamp w = stamp(rir.wav_path);
      if (w.not_regular) {
        problems.error(rir.wav_path, "is not a regular file (a device, a pipe or a folder?)",
                       "replace it with the RIR's wav file");
        continue;
      }
      if (!w.exists) {
        problems.error(rir.wav_path,
                       "split entry " + where + " " + json_quoted(id) + " has no rir.wav",
                       "restore the file or remove the id from " + split_path);
        continue;
      }
      const std::string rx_path = (fs::path(folder) / "rx_pos.txt").string();
      const std::string tx_path = (fs::path(folder) / "tx_pos.txt").string();
      const std::optional<RafPose> pose = parse_raf_pose(
          read_file_text(rx_path), rx_path, read_file_text(tx_path), tx_path, problems);
      if (!pose) continue;
      rir.mic = pose->mic;
      rir.source = pose->source;
      rir.raw_yaw_deg = pose->yaw_deg;
      rir.heading_deg = round_half_even(rir.raw_yaw_deg);
      rir.rot = encode_heading(rir.heading_deg);
      (li == 0 ? set.train : set.test).push_back(set.size());
      set.rirs.push_back(std::move(rir));
      idx.wav.push_back(w);
    }
  }
  if (set.train.empty())
    problems.error(split_path, "no usable train RIRs", "check data-split.json and data/");
  if (set.test.empty())
    problems.warning(split_path, "no usable test RIRs", "audio metrics will be skipped");
  return idx;
}

int64_t raf_features(const std::string& wav, int64_t max_len, float* out, ProblemList& problems) {
  // First 0.32 s (zero-padded when a file is shorter, which the released RIRs never are), STFT
  // n_fft 1024 / win 512 / hop 256 -> 61 frames, of which max_len (60) are kept.
  std::vector<float> x = read_mono48k(wav, problems);
  problems.throw_if_errors(wav);
  x.resize(static_cast<size_t>(kRafSamples), 0.0f);
  const dsp::StftParams params = dsp::StftParams::raf();
  const dsp::Matrix mag = dsp::magnitude(dsp::stft(x, params));
  write_padded_log({mag.data.data()}, params.n_freq(), mag.cols, max_len, out);
  return mag.cols;
}

std::vector<std::vector<float>> raf_waveform(const std::string& wav, int64_t length) {
  ProblemList problems;  // warnings (silence) were reported when the features were made
  std::vector<float> x = read_mono48k(wav, problems);
  x.resize(static_cast<size_t>(length), 0.0f);
  return {std::move(x)};
}

}  // namespace neraf::data::detail
