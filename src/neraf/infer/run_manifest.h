#pragma once
// What commands read back from a run's data manifest, RUN/data.json (run.h), parsed and checked
// without LibTorch (fuzz/fuzz_data_manifest.cpp feeds them any JSON): the scenes of a multi-scene
// run, the "audio" entry and camera intrinsics. A damaged value is a neraf::Error naming the file,
// never a library exception or a silently wrapped number. run.cpp and audio_run.cpp write the
// manifest and load the run around them.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "neraf/data/audio_layout.h"
#include "neraf/data/transforms_json.h"  // Intrinsics
#include "neraf/dsp/stft.h"

namespace neraf::infer {

// Multi-scene runs (neraf train with 2+ --data, modality audio): RUN/data.json is
// {"format", "scenes": [M_0, M_1, ...]}, each M_s a one-scene manifest (make_data_manifest of the
// scene, with its "audio" entry) plus its "name" (the dataset folder's name, or "scene<s>" when
// two folders share one). A loaded scene of such a run (load_audio_run with a scene) carries M_s
// as its manifest, so everything downstream sees an ordinary one-scene run.
bool is_multiscene(const nlohmann::json& data_manifest);
// {} for one scene; "?" for a scene without a name (a damaged manifest).
std::vector<std::string> scene_names(const nlohmann::json& data_manifest);
// The scene `selector` names (its name, or its index 0..N−1) in a multi-scene manifest;
// neraf::Error naming `run_dir`, `flag` and the scenes when there is none.
int64_t find_scene(const nlohmann::json& data_manifest, const std::string& selector,
                   const std::string& run_dir, const std::string& flag = "--scene");

// neraf::Error naming `where` (RUN/data.json) when the dataset path it records ("data", and each
// scene's) holds a control character: a NUL would end the path early, so the folder before it
// would be read without a word.
void check_data_paths(const nlohmann::json& data_manifest, const std::string& where);

// The acoustic field's data, from the "audio" entry of RUN/data.json (make_audio_manifest,
// audio_run.h) or an exported model's header.
struct AudioRunInfo {
  data::AudioLayout layout = data::AudioLayout::soundspaces;
  int sample_rate = 22050;  // 22050 SoundSpaces, 48000 RAF
  dsp::StftParams stft;     // soundspaces() / raf()
  int64_t n_freq = 257;
  int64_t max_len = 78;  // frames per RIR (T)
  // The frames the model's time encoding spans when it predicts fewer (a multi-scene run's scene
  // of its own length: the longest scene's frames); 0 = max_len.
  int64_t time_frames = 0;
  int64_t model_frames() const { return time_frames > 0 ? time_frames : max_len; }
  int channels = 2;             // C
  int64_t waveform_length = 0;  // GT eval waveform length (SoundSpaces max_len·hop, RAF 15360)
  data::Aabb aabb;              // train audio aabb (positions are normalised with it)
};

// The "audio" entry of RUN/data.json, checked: neraf::Error naming `where` when a key is missing
// or of the wrong type ("incomplete") or a value is out of its range ("damaged": sample rate,
// channels, STFT sizes, n_freq = n_fft/2 + 1, max_len, a box that is finite and not inside out).
// A scene's audio.scene_frames (multi-scene runs) below max_len becomes max_len, with max_len as
// time_frames.
AudioRunInfo audio_info_from_manifest(const nlohmann::json& audio, const std::string& where);

// {"fx","fy","cx","cy","width","height"[,"k1","k2","k3","p1","p2"]} ↔ Intrinsics (checked;
// errors name `where`).
data::Intrinsics intrinsics_from_json(const nlohmann::json& j, const std::string& where);
nlohmann::json intrinsics_json(const data::Intrinsics& k);

}  // namespace neraf::infer
