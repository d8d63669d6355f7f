// SoundSpaces 1.0 (Replica) in the layout the published NeRAF code reads (neraf-reference.md §3.2):
//   <scene>/metadata/points.txt                          idx \t x \t y \t z  (Habitat, y up)
//   <scene>/metadata_AudioNeRF/split.json                {"train": ["<rot>/<r>_<s>", ...], "test":
//   [...]} <scene>/binaural_rirs/<rot>/<r>_<s>.wav              44.1 kHz, 2 channels
//   <scene>/binaural_magnitudes_sr22050/<rot>/<r>_<s>.npy  optional [2, 257, T] magnitudes
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "neraf/data/audio_probe.h"
#include "neraf/data/rir_check.h"
#include "neraf/data/rir_layouts.h"
#include "neraf/dsp/resample.h"
#include "neraf/dsp/stft.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/io/npy.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data::detail {
namespace {

std::string join(const std::string& a, const std::string& b) { return (fs::path(a) / b).string(); }

// "<rot>/<r>_<s>" -> rot, r, s. False when malformed.
bool parse_entry(const std::string& e, int& rot, long& r, long& s) {
  const size_t slash = e.find('/');
  if (slash == std::string::npos) return false;
  const size_t under = e.find('_', slash + 1);
  if (under == std::string::npos) return false;
  auto to_long = [](const std::string& t, long& v) {
    if (t.empty()) return false;
    char* end = nullptr;
    errno = 0;
    v = std::strtol(t.c_str(), &end, 10);
    return errno == 0 && *end == '\0';
  };
  long rl = 0;
  if (!to_long(e.substr(0, slash), rl) || !to_long(e.substr(slash + 1, under - slash - 1), r) ||
      !to_long(e.substr(under + 1), s))
    return false;
  rot = static_cast<int>(rl);
  return true;
}

std::vector<float> clipped(std::vector<float> x) {
  for (float& v : x) v = std::clamp(v, -1.0f, 1.0f);
  return x;
}

// Reads a SoundSpaces wav as [2][n] (an empty, header-only file gives two empty channels, as the
// reference's zero-length read does), with the checks validation runs on it.
std::vector<std::vector<float>> read_binaural(const std::string& wav, ProblemList& problems) {
  const AudioProbe p = probe_audio(wav);
  require(p.ok, wav + ": " + p.error);
  require(p.sample_rate == kSoundSpacesWavRate,
          wav + ": sample rate " + std::to_string(p.sample_rate) +
              " Hz, SoundSpaces RIRs must be 44100 Hz; resample the file to 44.1 kHz");
  require(p.channels == 2, wav + ": " + std::to_string(p.channels) +
                               " channel(s), SoundSpaces RIRs must be binaural (2 channels)");
  if (p.frames == 0) return {{}, {}};
  io::AudioBuffer a = io::read_audio(wav);
  check_rir_samples(wav, a.channels, problems);
  return std::move(a.channels);
}

}  // namespace

RirIndex index_soundspaces(const std::string& dir, bool use_magnitude_files,
                           ProblemList& problems) {
  RirIndex idx;
  RirSet& set = idx.set;
  set.layout = AudioLayout::soundspaces;
  set.root = dir;
  set.wav_sample_rate = kSoundSpacesWavRate;
  set.sample_rate = kSoundSpacesRate;
  set.channels = 2;
  set.stft = dsp::StftParams::soundspaces();
  set.n_freq = set.stft.n_freq();

  // Points: idx -> [x, z, -y] (Habitat y-up to the frame NeRAF uses; no height offset).
  const std::string points_path = join(dir, "metadata/points.txt");
  std::map<long, geometry::Vec3> points;
  {
    std::ifstream in(points_path);
    if (!in.good()) {
      problems.error(points_path, "missing or unreadable",
                     "copy metadata/points.txt from the SoundSpaces 1.0 release of this scene");
      return idx;
    }
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
      ++line_no;
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::istringstream ls(line);
      std::string tok[4];
      int n = 0;
      while (n < 4 && ls >> tok[n]) ++n;
      std::string extra;
      long id = 0;
      double v[3];
      bool ok = n == 4;
      if (ok) {
        char* end = nullptr;
        id = std::strtol(tok[0].c_str(), &end, 10);
        ok = *end == '\0';
        for (int k = 0; k < 3 && ok; ++k) {
          v[k] = std::strtod(tok[k + 1].c_str(), &end);
          ok = *end == '\0';
        }
      }
      const std::string where = "line " + std::to_string(line_no);
      if (!ok) {
        problems.error(points_path,
                       where + ": expected 'idx<TAB>x<TAB>y<TAB>z', got '" + line + "'",
                       "fix the line");
        continue;
      }
      if (!sane_coordinates(v, 3)) {
        problems.error(points_path,
                       where + ": point " + std::to_string(id) +
                           " has a NaN, infinite or implausible coordinate (|x| > 10000 m)",
                       "fix the coordinates (metres) or remove the point and the RIRs that use it");
        continue;
      }
      if (points.count(id)) {
        problems.error(points_path, where + ": duplicate point index " + std::to_string(id),
                       "give every point a unique index");
        continue;
      }
      points[id] = {v[0], v[2], -v[1]};
    }
  }

  // Split: metadata_AudioNeRF/split.json (the code's path); the repo ships it at the scene root.
  std::string split_path = join(dir, "metadata_AudioNeRF/split.json");
  std::error_code ec;
  if (!fs::exists(split_path, ec)) {
    const std::string alt = join(dir, "split.json");
    if (fs::exists(alt, ec)) {
      problems.warning(alt, "read from the scene root",
                       "the published code expects it in metadata_AudioNeRF/split.json; move it");
      split_path = alt;
    } else {
      problems.error(split_path, "missing",
                     "copy the scene's split.json from the NeRAF repository to "
                     "metadata_AudioNeRF/split.json");
      return idx;
    }
  }
  json split;
  try {
    split = io::read_json(split_path);
  } catch (const Error& e) {
    problems.error("", e.what(), "");
    return idx;
  }
  if (!split.is_object() || !split.contains("train") || !split["train"].is_array() ||
      !split.contains("test") || !split["test"].is_array()) {
    problems.error(split_path, "must be {\"train\": [...], \"test\": [...]}",
                   "use the split.json of the NeRAF repository");
    return idx;
  }

  std::set<std::string> seen;
  int64_t npy_found = 0;
  for (const char* name : {"train", "test"}) {
    const json& list = split[name];
    for (size_t k = 0; k < list.size(); ++k) {
      const std::string where = std::string(name) + "[" + std::to_string(k) + "]";
      if (!list[k].is_string()) {
        problems.error(split_path, where + " is not a string", "entries look like \"270/122_44\"");
        continue;
      }
      const std::string entry = list[k].get<std::string>();
      int rot = 0;
      long r = 0, s = 0;
      if (!parse_entry(entry, rot, r, s)) {
        problems.error(split_path,
                       where + " \"" + entry + "\" is not \"<rot>/<receiver>_<source>\"",
                       "entries look like \"270/122_44\"");
        continue;
      }
      if (!seen.insert(entry).second) {
        problems.error(split_path, where + " \"" + entry + "\" is listed twice (duplicate id)",
                       "remove the duplicate entry");
        continue;
      }
      const auto pr = points.find(r), ps = points.find(s);
      if (pr == points.end() || ps == points.end()) {
        problems.error(split_path,
                       where + " \"" + entry + "\" uses point " +
                           std::to_string(pr == points.end() ? r : s) +
                           ", which metadata/points.txt does not define",
                       "use the points.txt and split.json of the same scene");
        continue;
      }
      Rir rir;
      rir.id = entry;
      const std::string stem =
          std::to_string(rot) + "/" + std::to_string(r) + "_" + std::to_string(s);
      rir.wav_path = join(dir, "binaural_rirs/" + stem + ".wav");
      const std::string npy = join(dir, "binaural_magnitudes_sr22050/" + stem + ".npy");
      rir.mic = pr->second;
      rir.source = ps->second;
      rir.heading_deg = rot;
      rir.raw_yaw_deg = rot;
      rir.rot = encode_heading(rot);
      const FileStamp w = stamp(rir.wav_path);
      if (w.not_regular) {
        problems.error(rir.wav_path, "is not a regular file (a device, a pipe or a folder?)",
                       "replace it with the RIR's wav file");
        continue;
      }
      if (!w.exists) {
        problems.error(rir.wav_path, "split entry " + where + " \"" + entry + "\" has no file",
                       "restore the wav or remove the entry from " + split_path);
        continue;
      }
      const FileStamp m = use_magnitude_files ? stamp(npy) : FileStamp{};
      if (m.exists) {
        ++npy_found;
        rir.magnitude_path = npy;
      }
      (std::string(name) == "train" ? set.train : set.test).push_back(set.size());
      set.rirs.push_back(std::move(rir));
      idx.wav.push_back(w);
      idx.npy.push_back(m);
    }
  }
  const int64_t n = set.size();
  idx.use_npy = use_magnitude_files && n > 0 && npy_found == n;
  if (npy_found > 0 && npy_found < n) {
    problems.warning(join(dir, "binaural_magnitudes_sr22050"),
                     std::to_string(n - npy_found) + " of " + std::to_string(n) +
                         " magnitude files are missing; all features are computed from the wavs",
                     "re-run the magnitude extraction or delete the folder");
  }
  if (!idx.use_npy)
    for (Rir& rir : set.rirs) rir.magnitude_path.clear();
  if (set.train.empty())
    problems.error(split_path, "no usable train RIRs", "check split.json and binaural_rirs/");
  if (set.test.empty())
    problems.warning(split_path, "no usable test RIRs", "audio metrics will be skipped");
  return idx;
}

int64_t soundspaces_num_frames(int64_t n) {
  const int64_t n1 = std::max<int64_t>(n, kSoundSpacesMinSamples);
  // dsp::resample returns round(n · to/from) samples.
  const int64_t n2 = std::llround(double(n1) * kSoundSpacesRate / kSoundSpacesWavRate);
  const int64_t len = std::max<int64_t>(n2 + 256, kSoundSpacesMinSamples);
  return dsp::stft_num_frames(static_cast<size_t>(len), dsp::StftParams::soundspaces());
}

int64_t soundspaces_features_from_wav(const std::string& wav, int64_t max_len, float* out,
                                      ProblemList& problems) {
  // process_audio.ipynb: clip, fix_length to 4410 if shorter, resample 44.1 -> 22.05 kHz, clip,
  // right-pad n_fft/2 = 256 zeros and to >= 4410 samples, |STFT(512, 128, 512)|.
  const auto channels = read_binaural(wav, problems);
  problems.throw_if_errors(wav);
  const dsp::StftParams params = dsp::StftParams::soundspaces();
  std::vector<dsp::Matrix> mags;
  for (const auto& ch : channels) {
    std::vector<float> x = clipped(ch);
    if (x.size() < size_t(kSoundSpacesMinSamples)) x.resize(kSoundSpacesMinSamples, 0.0f);
    std::vector<float> y = clipped(dsp::resample(x, kSoundSpacesWavRate, kSoundSpacesRate));
    y.resize(std::max<size_t>(y.size() + 256, kSoundSpacesMinSamples), 0.0f);
    mags.push_back(dsp::magnitude(dsp::stft(y, params)));
  }
  const int64_t n_frames = mags[0].cols;
  require(n_frames == mags[1].cols, wav + ": internal error: channel STFT lengths differ");
  write_padded_log({mags[0].data.data(), mags[1].data.data()}, params.n_freq(), n_frames, max_len,
                   out);
  return n_frames;
}

int64_t soundspaces_features_from_npy(const std::string& npy, int64_t max_len, float* out,
                                      ProblemList& problems) {
  const io::NpyArray a = io::read_npy(npy);
  const int64_t n_freq = dsp::StftParams::soundspaces().n_freq();
  check_magnitudes(npy, a, n_freq, problems);
  problems.throw_if_errors(npy);
  const int64_t n_frames = a.shape[2];
  write_padded_log({a.data.data(), a.data.data() + n_freq * n_frames}, n_freq, n_frames, max_len,
                   out);
  return n_frames;
}

std::vector<std::vector<float>> soundspaces_waveform(const std::string& wav, int64_t length) {
  // SoundSpacesDataset.get_data_eval: clip, resample to 22.05 kHz, cut / zero-pad (no minimum
  // length and no second clip on this path). An empty file is all zeros.
  ProblemList problems;  // warnings (silence) were reported when the features were made
  auto channels = read_binaural(wav, problems);
  std::vector<std::vector<float>> out;
  for (auto& ch : channels) {
    std::vector<float> y =
        ch.empty() ? std::vector<float>{}
                   : dsp::resample(clipped(std::move(ch)), kSoundSpacesWavRate, kSoundSpacesRate);
    y.resize(static_cast<size_t>(length), 0.0f);
    out.push_back(std::move(y));
  }
  return out;
}

}  // namespace neraf::data::detail
