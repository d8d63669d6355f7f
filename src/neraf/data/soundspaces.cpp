// SoundSpaces 1.0 (Replica) in the layout the published NeRAF code reads (neraf-reference.md §3.2):
//   <scene>/metadata/points.txt              idx \t x \t y \t z  (Habitat, y up)
//   <scene>/metadata_AudioNeRF/split.json    {"train": ["<rot>/<r>_<s>", ...], "test": [...]}
//   <scene>/binaural_rirs/<rot>/<r>_<s>.wav  44.1 kHz, 2 channels
//   <scene>/binaural_magnitudes_sr22050/<rot>/<r>_<s>.npy  optional [2, 257, T] magnitudes
// points.txt and split.json are parsed by pose_files.h; this file checks the files they name.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "neraf/data/audio_probe.h"
#include "neraf/data/pose_files.h"
#include "neraf/data/rir_check.h"
#include "neraf/data/rir_layouts.h"
#include "neraf/dsp/resample.h"
#include "neraf/dsp/stft.h"
#include "neraf/io/audio_file.h"
#include "neraf/io/json_file.h"
#include "neraf/io/npy.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data::detail {
namespace {

std::string join(const std::string& a, const std::string& b) { return (fs::path(a) / b).string(); }

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
  const std::optional<std::string> points_text = read_file_text(points_path);
  if (!points_text) {
    problems.error(points_path, "missing or unreadable",
                   "copy metadata/points.txt from the SoundSpaces 1.0 release of this scene");
    return idx;
  }
  const std::map<long, geometry::Vec3> points =
      parse_points_txt(*points_text, points_path, problems);

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
  int64_t npy_found = 0;
  const bool lists =
      parse_soundspaces_split(split, split_path, points, problems, [&](const SoundSpacesEntry& e) {
        Rir rir;
        rir.id = e.id;
        // The entry is written as its numbers print (parse_soundspaces_split): it names the files.
        rir.wav_path = join(dir, "binaural_rirs/" + e.id + ".wav");
        const std::string npy = join(dir, "binaural_magnitudes_sr22050/" + e.id + ".npy");
        rir.mic = e.mic;
        rir.source = e.source_position;
        rir.heading_deg = e.rot;
        rir.raw_yaw_deg = e.rot;
        rir.rot = encode_heading(e.rot);
        const FileStamp w = stamp(rir.wav_path);
        if (w.not_regular) {
          problems.error(rir.wav_path, "is not a regular file (a device, a pipe or a folder?)",
                         "replace it with the RIR's wav file");
          return;
        }
        if (!w.exists) {
          problems.error(rir.wav_path,
                         "split entry " + e.where + " " + json_quoted(e.id) + " has no file",
                         "restore the wav or remove the entry from " + split_path);
          return;
        }
        const FileStamp m = use_magnitude_files ? stamp(npy) : FileStamp{};
        if (m.exists) {
          ++npy_found;
          rir.magnitude_path = npy;
        }
        (e.train ? set.train : set.test).push_back(set.size());
        set.rirs.push_back(std::move(rir));
        idx.wav.push_back(w);
        idx.npy.push_back(m);
      });
  if (!lists) return idx;
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
