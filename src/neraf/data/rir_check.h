#pragma once
// Internal to data/: the checks of one RIR's files that both `neraf info` (validate.cpp) and the
// loaders (rir_set.cpp and the feature recipes) run, so that what info accepts is exactly what
// training accepts. Each appends Problems naming the file; errors are what the loaders throw.
#include <cstdint>
#include <string>
#include <vector>

#include "neraf/data/audio_probe.h"
#include "neraf/data/problem.h"
#include "neraf/data/rir_set.h"
#include "neraf/io/npy.h"

namespace neraf::data::detail {

// Longest impulse response accepted (s). The most reverberant rooms measured decay in ~15 s; a
// longer file is a recording, and with SoundSpaces' automatic max_len every RIR would be padded
// to it (one 10-minute file made a 17 GB feature cache).
constexpr double kMaxRirSeconds = 30.0;
// Largest |coordinate| accepted in a pose file (m): 10 km. Scenes are rooms; 1e300 is a typo or
// damage, and it would silently zero every normalised position (or overflow to infinity).
constexpr double kMaxAbsCoordinate = 1e4;
// Largest magnitude accepted in a published .npy magnitude file: the STFT of audio at
// io::kMaxAbsSample through a 512-point Hann window is below 2.6e5.
constexpr float kMaxMagnitude = 1e6f;
// A cache at least this large whose padding to the longest RIR makes it kMaxPaddingFactor times
// the features themselves is refused (one outlier RIR, not the data, would fill the disk).
constexpr double kPaddingCheckBytes = 1e9;
constexpr double kMaxPaddingFactor = 8.0;

// "|v| ≤ kMaxAbsCoordinate and finite" for every value.
bool sane_coordinates(const double* v, int n);

struct RirHeader {
  AudioProbe probe;          // the wav's header
  int64_t stft_frames = -1;  // the RIR's own STFT length (SoundSpaces: of the features' source,
                             // the .npy when the set uses them); -1 when a problem hides it
};

// Header checks of RIR i of `set`: the wav (readable, not truncated, sample rate, channels,
// length ≤ kMaxRirSeconds; empty → warning; RAF shorter than 0.32 s → warning) and, when the set
// uses magnitude files, the .npy header (shape [2, 257, T], length). Cheap: no samples read.
RirHeader check_rir_header(const RirSet& set, int64_t i, ProblemList& problems);

// Checks of the samples a recipe or the validator read from `wav` (NaN / infinite / huge samples
// are already refused by io::read_audio): all samples zero → a warning (silence, like an empty
// file).
void check_rir_samples(const std::string& wav, const std::vector<std::vector<float>>& channels,
                       ProblemList& problems);

// A SoundSpaces magnitude file: shape [2, n_freq, T ≥ 1], every value finite, ≥ 0 and
// ≤ kMaxMagnitude.
void check_magnitudes(const std::string& npy, const io::NpyArray& a, int64_t n_freq,
                      ProblemList& problems);

// SoundSpaces' automatic max_len pads every RIR to the longest: an error naming the longest RIR
// (and the estimated cache size) when that makes a cache of ≥ kPaddingCheckBytes more than
// kMaxPaddingFactor times the unpadded features. `frames`: each RIR's own STFT length (≤ 0 are
// skipped).
void check_padded_cache_size(const RirSet& set, const std::vector<int64_t>& frames, bool half,
                             ProblemList& problems);

// Estimated cache bytes for n RIRs of max_len frames.
double cache_bytes(const RirSet& set, int64_t max_len, bool half);

// Runs check_rir_header for every RIR in parallel; problems in RIR order. frames[i] is
// RirHeader::stft_frames.
ProblemList check_rir_headers(const RirSet& set, std::vector<RirHeader>& headers);

}  // namespace neraf::data::detail
