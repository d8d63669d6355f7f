#pragma once
// `neraf synth`: a whole dataset from one scene — photos (image_renderer), RIRs (RirSimulator) and
// the files of the chosen layout (layout_writers), in one output folder:
//
//   soundspaces (NeRAF's SoundSpaces layout, binaural 44.1 kHz)   raf (RAF layout, mono 48 kHz)
//     scene.json, synth_info.json, plan.png                        scene.json, synth_info.json,
//                                                                  plan.png
//     transforms.json + images/{train,eval}_frame_XXXXX.png        transforms.json +
//     images/frame_XXXXX.png metadata/points.txt data/<6-digit id>/rir.wav
//     metadata_AudioNeRF/split.json                                data/<id>/rx_pos.txt, tx_pos.txt
//     binaural_rirs/<heading>/<r>_<s>.wav                          metadata/data-split.json
//
// Deterministic: the same scene + seed give byte-identical files for any thread count.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "neraf/sim/cameras.h"
#include "neraf/sim/scene.h"

namespace neraf::sim {

struct SynthOptions {
  std::string layout = "soundspaces";  // "soundspaces" | "raf"
  std::string out_dir;
  uint64_t seed = 0;
  bool force = false;     // replace a non-empty out_dir (only once the new dataset is complete)
  bool progress = true;   // progress bars on stderr
  std::string hrtf_path;  // SOFA file for binaural RIRs; empty: Hrtf::kDefaultSofa
  // > 0: every RIR is scaled by this instead of the automatic gain (which puts the set's peak at
  // 0.5), so that a second set of the same room shares the first one's scale.
  double gain = 0;
};

// One RIR file of the plan.
struct RirJob {
  std::string file;    // relative to out_dir: "binaural_rirs/90/12_3.wav", "data/000012/rir.wav"
  std::string name;    // split entry: "90/12_3" (SoundSpaces), "000012" (RAF)
  int source = 0;      // index into scene.sources
  int microphone = 0;  // index into SynthPlan::microphones
  double mic_yaw_deg = 0;  // receiver heading (SoundSpaces); 0 for RAF's omni microphones
};

struct SynthPlan {
  std::string layout;
  int sample_rate = 0;
  bool binaural = false;
  std::vector<Vec3> microphones;  // SoundSpaces points 0..M-1 (sources follow as M..M+S-1)
  std::vector<double> headings_deg;
  std::vector<RirJob> jobs;
  std::vector<CameraView> train_cameras, eval_cameras;
};

// What a layout will write (no pictures or audio are computed). Throws neraf::Error for an
// unknown layout.
SynthPlan plan_synthesis(const Scene& scene, const std::string& layout, uint64_t seed);

// How big a dataset is, from the scene's counts alone (no plan, no positions beyond the grid's),
// so an absurd request fails before any memory is allocated or file written.
struct SynthSize {
  int64_t microphones = 0, headings = 1, sources = 0, rirs = 0;
  int channels = 1;
  int64_t samples_per_rir = 0;
  int64_t images = 0;
  double rir_bytes = 0;    // float WAVs
  double image_bytes = 0;  // raw RGB (an upper bound of the PNGs)
  double total_bytes() const { return rir_bytes + image_bytes; }
};
SynthSize estimate_synthesis(const Scene& scene, const std::string& layout);

// The largest dataset `neraf synth` writes: SoundSpaces' biggest scene (apartment_1) has ~124k
// binaural RIRs of ~44 GB; beyond these a typo (a million microphones) would fill the disk for
// hours before failing.
constexpr int64_t kMaxSynthRirs = 250000;
constexpr double kMaxSynthBytes = 64e9;

// Throws neraf::Error (one line: `origin`, the counts, the estimated size and the limits) when the
// dataset exceeds kMaxSynthRirs or kMaxSynthBytes. `count_flags` names the flags that set the
// counts (e.g. "--mic-count"), for the fix.
void check_synthesis_size(const Scene& scene, const std::string& layout, const std::string& origin,
                          const std::string& count_flags = "");

// Throws neraf::Error (naming `origin` and acoustics.rir_length_s) when no RIR of the plan could
// hold a sound: every source-microphone pair is farther apart than the sound travels within
// rir_length_s, so every RIR would be all zeros (the direct path arrives first).
void check_sound_reaches_microphones(const Scene& scene, const SynthPlan& plan,
                                     const std::string& origin);

struct SynthSummary {
  std::string layout, out_dir;
  int sample_rate = 0, channels = 0;
  int num_microphones = 0, num_headings = 0, num_sources = 0;
  int64_t num_rirs = 0, num_train_rirs = 0, num_test_rirs = 0;
  int num_train_images = 0, num_eval_images = 0;
  double gain = 1;  // one scene-wide factor applied to every RIR (see synthesize)
  double peak = 0;  // largest |sample| written
  double image_seconds = 0, rir_seconds = 0, total_seconds = 0;
};

// Writes the dataset, built in a temporary folder beside out_dir and renamed into place (a failure
// leaves nothing). Refuses a non-empty out_dir unless options.force. Every RIR is scaled by one
// scene-wide gain = min(1, 0.5 / peak of the closest source-microphone pairs) so no sample clips
// in NeRAF's loaders (which clip to [-1, 1]) and relative levels stay physical; the gain is
// recorded in synth_info.json.
SynthSummary synthesize(const Scene& scene, const SynthOptions& options);

// The gain a `neraf synth` folder's RIRs were scaled by (its synth_info.json); none for a folder
// without that file (e.g. a real dataset). neraf::Error when the file has no positive gain.
std::optional<double> synthesized_gain(const std::string& dataset_dir);

// Whether two `neraf synth` folders hold the same room: the first key of their scene.json that
// differs, leaving out where the microphones, sources and cameras were put ("size", "furniture",
// "materials", ...); none when the rooms match or a folder has no scene.json (e.g. real data).
std::optional<std::string> room_difference(const std::string& dataset_a,
                                           const std::string& dataset_b);
// The same for a scene and a `neraf synth` folder.
std::optional<std::string> room_difference(const Scene& scene, const std::string& dataset);

}  // namespace neraf::sim
