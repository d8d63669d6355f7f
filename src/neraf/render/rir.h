#pragma once
// Rendering room impulse responses from a trained acoustic field: poses in, log-magnitude STFT
// out (the model), linear magnitude → Griffin-Lim → waveform (neraf-reference.md §4.1, §5).
//
// The model side is abstracted as a function (LogStftFn) so that rendering, loudness maps and
// auralization can be tested without a trained run; the CLI binds it to a run's audio model.
#include <torch/types.h>

#include <cstdint>
#include <functional>
#include <string>

#include "neraf/data/rir_set.h"
#include "neraf/dsp/stft.h"
#include "neraf/geometry/vec.h"
#include "neraf/io/audio_file.h"

namespace neraf::render {

// What rendering needs to know about a run's acoustic field.
struct AudioModelInfo {
  data::AudioLayout layout = data::AudioLayout::soundspaces;
  int sample_rate = 22050;  // rate of the waveforms the STFT describes (22050 / 48000)
  dsp::StftParams stft = dsp::StftParams::soundspaces();
  int channels = 2;      // 2 binaural (SoundSpaces) / 1 (RAF)
  int64_t max_len = 78;  // STFT frames per RIR
  data::Aabb aabb;       // the train audio bounding box (train mics ± 1 m), dataset frame
};

// Predicted log-magnitudes log(|STFT| + 1e-3) for B poses (dataset frame, metres, y up):
// mic [B, 3], src [B, 3] float64; yaw [B] float64 degrees (the orientation the model was trained
// on: the receiver heading for SoundSpaces, the source yaw for RAF) → [B, C, F, T] float32.
using LogStftFn = std::function<torch::Tensor(const torch::Tensor& mic, const torch::Tensor& src,
                                              const torch::Tensor& yaw)>;

// "X,Y,Z": three finite numbers separated by commas (spaces around them allowed). Errors name
// `flag`, e.g. "--mic: expected X,Y,Z (three numbers in metres), got \"1,2\"".
geometry::Vec3 parse_position(const std::string& text, const std::string& flag);

// True when every coordinate of p lies strictly inside the box: NeRAF normalises positions with
// the train audio aabb and replaces a position outside the open box by the zero vector, so the
// prediction there is not about that position any more.
bool inside_open_box(const geometry::Vec3& p, const data::Aabb& box);

struct RirRenderOptions {
  uint64_t seed = 0;  // Griffin-Lim's initial random phases (32 iterations, momentum 0.99)
};

// Predicted log-magnitude [C, F, T] → waveform (C channels, hop·(T − 1) samples, `sample_rate`).
io::AudioBuffer rir_from_log_stft(const torch::Tensor& log_stft, const dsp::StftParams& stft,
                                  int sample_rate, const RirRenderOptions& options = {});

// One pose through `predict` and Griffin-Lim. The caller warns about poses outside the aabb.
io::AudioBuffer render_rir(const LogStftFn& predict, const AudioModelInfo& info,
                           const geometry::Vec3& mic, const geometry::Vec3& src, double yaw_deg,
                           const RirRenderOptions& options = {});

}  // namespace neraf::render
