// RAF (Real Acoustic Fields) in the layout the published NeRAF code reads (neraf-reference.md
// §3.3):
//   <room>/metadata/data-split.json   {"train": [[ids]], "validation": [[...], ...], "test":
//   [[ids]]} <room>/data/<id>/rir.wav          mono, 48 kHz <room>/data/<id>/rx_pos.txt "x,y,z"
//   microphone (omni), m <room>/data/<id>/tx_pos.txt       "qx,qy,qz,qw,x,y,z"     source
//   orientation (real last) + position
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "neraf/data/audio_probe.h"
#include "neraf/data/rir_check.h"
#include "neraf/data/rir_layouts.h"
#include "neraf/dsp/stft.h"
#include "neraf/geometry/quaternion.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data::detail {
namespace {

// All numbers of a one-line text file separated by commas and/or white space. False if a token
// is not a number.
bool read_numbers(const std::string& path, std::vector<double>& out, std::string& text) {
  std::ifstream in(path);
  if (!in.good()) return false;
  std::stringstream ss;
  ss << in.rdbuf();
  text = ss.str();
  std::string t = text;
  std::replace(t.begin(), t.end(), ',', ' ');
  std::istringstream is(t);
  std::string tok;
  out.clear();
  while (is >> tok) {
    char* end = nullptr;
    const double v = std::strtod(tok.c_str(), &end);
    if (*end != '\0') return false;
    out.push_back(v);
  }
  return true;
}

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
  auto first_list = [&](const char* name) -> const json* {
    if (!split.is_object() || !split.contains(name) || !split[name].is_array() ||
        split[name].empty() || !split[name][0].is_array())
      return nullptr;
    return &split[name][0];  // NeRAF reads ['train'][0] and ['test'][0]
  };
  const json* lists[2] = {first_list("train"), first_list("test")};
  if (!lists[0] || !lists[1]) {
    problems.error(split_path, "must hold {\"train\": [[ids]], \"test\": [[ids]]}",
                   "use the RAF repository's data-split file of this room");
    return idx;
  }

  std::set<std::string> seen;
  const char* names[2] = {"train", "test"};
  for (int li = 0; li < 2; ++li) {
    const json& list = *lists[li];
    for (size_t k = 0; k < list.size(); ++k) {
      const std::string where = std::string(names[li]) + "[0][" + std::to_string(k) + "]";
      std::string id;
      if (list[k].is_string()) {
        id = list[k].get<std::string>();
      } else if (list[k].is_number_integer()) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%06lld", static_cast<long long>(list[k].get<int64_t>()));
        id = buf;
      } else {
        problems.error(split_path, where + " is not an id",
                       "ids are numbers or \"000123\" strings");
        continue;
      }
      if (id.empty() || id.find('/') != std::string::npos || id == "." || id == "..") {
        problems.error(split_path, where + " \"" + id + "\" is not an id",
                       "ids name folders of data/ (\"000123\"), not paths");
        continue;
      }
      std::string folder = (fs::path(dir) / "data" / id).string();
      if (!fs::is_directory(folder, ec) && list[k].is_string()) {
        // "123" written without the zero padding of the folder names
        char* end = nullptr;
        const long long v = std::strtoll(id.c_str(), &end, 10);
        if (*end == '\0') {
          char buf[32];
          std::snprintf(buf, sizeof buf, "%06lld", v);
          if (fs::is_directory(fs::path(dir) / "data" / buf, ec)) {
            id = buf;
            folder = (fs::path(dir) / "data" / id).string();
          }
        }
      }
      if (!seen.insert(id).second) {
        problems.error(split_path, where + " \"" + id + "\" is listed twice (duplicate id)",
                       "remove the duplicate id");
        continue;
      }
      if (!fs::is_directory(folder, ec)) {
        problems.error(folder, "split entry " + where + " \"" + id + "\" has no folder",
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
        problems.error(rir.wav_path, "split entry " + where + " \"" + id + "\" has no rir.wav",
                       "restore the file or remove the id from " + split_path);
        continue;
      }
      std::vector<double> rx, tx;
      std::string text;
      const std::string rx_path = (fs::path(folder) / "rx_pos.txt").string();
      const std::string tx_path = (fs::path(folder) / "tx_pos.txt").string();
      if (!read_numbers(rx_path, rx, text) || rx.size() != 3) {
        problems.error(rx_path, "missing or not \"x,y,z\"",
                       "restore the file from the RAF release");
        continue;
      }
      if (!read_numbers(tx_path, tx, text) || tx.size() != 7) {
        problems.error(tx_path, "missing or not \"qx,qy,qz,qw,x,y,z\"",
                       "restore the file from the RAF release");
        continue;
      }
      if (!sane_coordinates(rx.data(), 3)) {
        problems.error(rx_path,
                       "microphone position has a NaN, infinite or implausible coordinate "
                       "(|x| > 10000 m)",
                       "fix the file (metres) or remove the id from the split");
        continue;
      }
      // The quaternion's scale does not matter (it is normalised), but 1e300 components overflow.
      const double qn = std::sqrt(tx[0] * tx[0] + tx[1] * tx[1] + tx[2] * tx[2] + tx[3] * tx[3]);
      if (!sane_coordinates(tx.data(), 7) || !(qn > 1e-9)) {
        problems.error(
            tx_path,
            "source pose has a NaN, infinite or implausible value (|x| > 10000) or a "
            "zero quaternion",
            "fix the file (qx,qy,qz,qw,x,y,z in metres) or remove the id from the split");
        continue;
      }
      rir.mic = {rx[0], rx[1], rx[2]};
      rir.source = {tx[4], tx[5], tx[6]};
      // Omni microphones: the orientation is the SOURCE yaw, scipy 'yxz' Euler angle about y.
      rir.raw_yaw_deg = geometry::yaw_yxz_deg({tx[0], tx[1], tx[2], tx[3]});
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
