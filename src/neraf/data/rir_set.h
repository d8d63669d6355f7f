#pragma once
// Measured/simulated room impulse responses of one scene (the audio half of a dataset), as the
// acoustic field consumes them (neraf-reference.md §2.5, §3).
//
// Poses stay in the dataset's own frame, in metres, exactly as the published NeRAF code uses
// them: SoundSpaces points `idx x y z` become [x, z, −y] (no height offset); RAF positions are
// used as written. Orientation is one integer heading θ (degrees), encoded as
// rot = ((cos θ + 1)/2, 0.5, (sin θ + 1)/2): the receiver heading (folder angle) for SoundSpaces,
// the source yaw round(as_euler('yxz')[0]) of tx_pos.txt's quaternion for RAF.
//
// Features: per RIR a log-magnitude STFT log(|STFT| + 1e-3), [C, F, max_len]; frames past the
// RIR's own length are filled with log(min|STFT| + 1e-3) (min over the whole RIR, all channels),
// longer RIRs are cut at max_len. They are computed once into a cache file and read slice by slice,
// so a 120k-RIR scene (≈24 GB of features) never has to fit in RAM or in the process's memory:
//   <scene>/.neraf_cache/<layout>_<16 hex digits>.bin   (or under RirLoadOptions::cache_dir)
// The hex digits hash the layout, feature parameters and every source file's path, size and
// modification time: editing, adding or removing a file makes a new cache (the stale one is
// deleted). File format: see feature_cache.h.
#include <torch/torch.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "neraf/data/audio_layout.h"  // AudioLayout, Aabb
#include "neraf/data/problem.h"
#include "neraf/dsp/stft.h"
#include "neraf/geometry/vec.h"

namespace neraf::data {

class FeatureCache;

// NeRAF's position normalisation: p' = (p − min)/(max − min); the WHOLE vector becomes 0 when any
// component of p' lies outside the open interval (0, 1).
geometry::Vec3 normalize_position(const geometry::Vec3& p, const Aabb& box);
torch::Tensor normalize_position(const torch::Tensor& p, const Aabb& box);  // [N, 3] -> [N, 3]

// ((cos θ + 1)/2, 0.5, (sin θ + 1)/2) with θ in degrees.
std::array<double, 3> encode_heading(int heading_deg);

struct Rir {
  std::string id;        // SoundSpaces "<rot>/<r>_<s>" (the split.json entry); RAF the folder id
  std::string wav_path;  // the impulse response
  std::string magnitude_path;   // SoundSpaces binaural_magnitudes_sr22050/<rot>/<r>_<s>.npy if
                                // present (its magnitudes are used instead of the wav's)
  geometry::Vec3 mic;           // m, dataset frame as NeRAF uses it
  geometry::Vec3 source;        // m
  int heading_deg = 0;          // θ that `rot` encodes (integer degrees)
  double raw_yaw_deg = 0;       // before rounding (RAF quaternion yaw; SoundSpaces = heading_deg)
  std::array<double, 3> rot{};  // encode_heading(heading_deg)
  int64_t num_frames = 0;  // the RIR's own STFT length before padding/cutting (0 until features
                           // are loaded)
};

struct RirLoadOptions {
  // Frames per RIR. 0 = automatic: RAF 60 (0.32 s); SoundSpaces the published value when the
  // dataset folder is named after a published scene (published_max_len), else the longest STFT
  // among the training RIRs (longer test RIRs are cut, as the reference cuts them).
  int64_t max_len = 0;
  bool load_features = true;    // false: poses and splits only (fast; features()/gather() throw)
  std::string cache_dir;        // "" = <scene>/.neraf_cache (falls back to ~/.cache/neraf/<hash>
                                // when the scene folder is not writable)
  bool half_precision = false;  // float16 cache: half the disk, ~1e-3 relative rounding
  bool use_magnitude_files = true;  // SoundSpaces: prefer the published .npy magnitudes
  bool progress = true;
  // Polled by the feature-cache workers (e.g. the train command's Ctrl-C flag): when it turns
  // true the build stops, its temporary file is removed and loading throws neraf::Error.
  const std::atomic<bool>* stop = nullptr;
};

// The cache precision as the commands take it (--cache-precision, a run's
// audio.cache_precision): "fp32" -> false, "fp16" -> true (RirLoadOptions::half_precision);
// neraf::Error naming `flag` for anything else.
bool parse_cache_precision(const std::string& text, const std::string& flag = "--cache-precision");

struct RirSet {
  AudioLayout layout = AudioLayout::soundspaces;
  std::string root;             // the dataset folder
  int wav_sample_rate = 0;      // rate of the files: 44100 (SoundSpaces) / 48000 (RAF)
  int sample_rate = 0;          // rate of features and eval waveforms: 22050 / 48000
  int channels = 0;             // 2 (binaural) / 1
  dsp::StftParams stft;         // soundspaces() / raf()
  int64_t n_freq = 0;           // 257 / 513
  int64_t max_len = 0;          // frames per RIR
  std::string max_len_source;   // how max_len was chosen: "--max-len", "published (office_4)",
                                // "longest training RIR", "RAF 0.32 s"
  std::string max_len_note;     // non-empty when the published value differs from the longest
                                // training RIR (printed when loading, kept in the run's data.json)
  int64_t waveform_length = 0;  // eval ground truth: max_len·128 (SoundSpaces) / 15360 (RAF)

  std::vector<Rir> rirs;             // train RIRs first (split order), then test
  std::vector<int64_t> train, test;  // indices into rirs
  Aabb audio_aabb;                   // train mic positions ± 1 m (the model's audio scene box)

  torch::Tensor mic_positions;     // [N, 3] float64
  torch::Tensor source_positions;  // [N, 3] float64
  torch::Tensor rots;              // [N, 3] float64 (encode_heading)
  std::string cache_path;          // the feature cache in use ("" without features)

  int64_t size() const { return static_cast<int64_t>(rirs.size()); }
  bool has_features() const { return cache_ != nullptr; }
  // FNV-1a of the RIR files' bytes the features were computed from ("" without features, or for
  // a cache written before neraf hashed them).
  std::string sources_hash() const;

  // Log-magnitude STFT of RIR i, padded/cut to max_len. [C, F, max_len] float32
  torch::Tensor features(int64_t i) const;
  // Slices for a training step: out[b] = features(rir[b])[:, :, frame[b]]. rir, frame: [B] int64.
  // [B, C, F] float32. One contiguous read per slice from the cache file.
  torch::Tensor gather(const torch::Tensor& rir, const torch::Tensor& frame) const;
  // Same into a preallocated [B, C, F] float32 contiguous tensor (no allocation per step).
  void gather_into(const torch::Tensor& rir, const torch::Tensor& frame, torch::Tensor& out) const;
  // Ground-truth waveform for evaluation, read from the wav: SoundSpaces clipped to [−1, 1],
  // resampled to 22.05 kHz, cut/zero-padded to waveform_length; RAF the first 15360 samples
  // (zero-padded if shorter). [C, waveform_length] float32
  torch::Tensor waveform(int64_t i) const;

  std::shared_ptr<const FeatureCache> cache_;  // the cached features (shared by copies)
};

// The same RIRs with only their first `frames` (2 ≤ frames ≤ rirs.max_len) frames per RIR: the
// features are read from the same cache, and the SoundSpaces evaluation waveforms are frames·hop
// samples (RAF's stay 0.32 s). A multi-scene run pads its scenes to the longest; each scene is
// scored and rendered at its own length through this.
RirSet first_frames(const RirSet& rirs, int64_t frames);

// SoundSpaces frames per RIR of the scenes the NeRAF paper trains on (office_4 78, room_2 84,
// apartment_1 101, apartment_2 86, frl_apartment_2 107, frl_apartment_4 103), by the name of the
// scene's folder; nullopt for any other name.
std::optional<int64_t> published_max_len(const std::string& scene_name);

// Detects the layout (SoundSpaces or RAF) of `dir` and loads it; throws neraf::Error listing the
// first problem (and how many more) when the dataset is broken.
RirSet load_rir_set(const std::string& dir, const RirLoadOptions& options = {});
RirSet load_soundspaces(const std::string& dir, const RirLoadOptions& options = {});
RirSet load_raf(const std::string& dir, const RirLoadOptions& options = {});

// Reads poses and splits without features and without throwing: problems (missing files, split
// entries without files, duplicate ids, NaN positions, ...) are appended to `problems`. Wav
// headers are NOT read here (see validate.h for the full check).
RirSet index_rir_set(const std::string& dir, AudioLayout layout, ProblemList& problems);

}  // namespace neraf::data
