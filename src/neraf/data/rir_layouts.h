#pragma once
// Internal to data/ (not part of the public API): the per-layout readers behind RirSet — index
// (poses, splits, file stamps) and the exact feature / waveform recipes of each layout.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "neraf/data/problem.h"
#include "neraf/data/rir_set.h"

namespace neraf::data::detail {

struct FileStamp {
  bool exists = false;       // a regular file (symlinks followed)
  bool not_regular = false;  // something else is there: a device, a FIFO, a folder
  int64_t size = 0;
  int64_t mtime_ns = 0;
};
FileStamp stamp(const std::string& path);

struct RirIndex {
  RirSet set;                  // poses, splits, paths; no features
  std::vector<FileStamp> wav;  // per RIR
  std::vector<FileStamp> npy;  // per RIR (SoundSpaces magnitude files; empty for RAF)
  bool use_npy = false;        // every RIR has a magnitude file and they are wanted
};

RirIndex index_soundspaces(const std::string& dir, bool use_magnitude_files, ProblemList& problems);
RirIndex index_raf(const std::string& dir, ProblemList& problems);

// Fills out[max_len][C][F] with the padded log-magnitudes; returns the RIR's own frame count.
// The samples / magnitudes read are checked as validation checks them (rir_check.h): errors are
// thrown, warnings (silence) appended to `problems`.
int64_t soundspaces_features_from_wav(const std::string& wav, int64_t max_len, float* out,
                                      ProblemList& problems);
int64_t soundspaces_features_from_npy(const std::string& npy, int64_t max_len, float* out,
                                      ProblemList& problems);
int64_t raf_features(const std::string& wav, int64_t max_len, float* out, ProblemList& problems);

// STFT frames the SoundSpaces recipe yields for a 44.1 kHz file of n samples (without reading it).
int64_t soundspaces_num_frames(int64_t n_samples_44k);

// Eval waveforms [C][length].
std::vector<std::vector<float>> soundspaces_waveform(const std::string& wav, int64_t length);
std::vector<std::vector<float>> raf_waveform(const std::string& wav, int64_t length);

// Shared by the recipes: writes log(mag + 1e-3) for t < min(T, max_len) and log(min + 1e-3)
// (min over all channels and frames) for the frames past T. mags[c] is [F][T] row-major.
void write_padded_log(const std::vector<const float*>& mags, int64_t n_freq, int64_t n_frames,
                      int64_t max_len, float* out);

// Runs fn(i) for i in [0, n) on OpenMP threads; rethrows the first exception after all stop.
void parallel_for_each(int64_t n, const std::function<void(int64_t)>& fn);

// SoundSpaces / RAF constants (neraf-reference.md §3.2-3.4).
constexpr int kSoundSpacesWavRate = 44100;
constexpr int kSoundSpacesRate = 22050;
constexpr int kSoundSpacesMinSamples = 4410;  // the notebook's fix_length / minimum length
constexpr int kRafRate = 48000;
constexpr int64_t kRafSamples = 15360;  // int(0.32 · 48000)
constexpr int64_t kRafMaxLen = 60;      // 61 STFT frames, the last dropped
constexpr float kLogEps = 1e-3f;

}  // namespace neraf::data::detail
