#pragma once
// Loudness maps of a trained acoustic field, as the reference's viz/loudness_maps (neraf-reference
// §5): a floor grid of microphone positions at one height, one fixed source and orientation; per
// position the predicted STFT's channel-0 RMS per frame (librosa.feature.rms on the spectrogram,
// frame_length = n_fft), summed over frames, and its natural log.
#include <torch/types.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "neraf/data/rir_set.h"
#include "neraf/geometry/vec.h"
#include "neraf/render/rir.h"

namespace neraf::render {

struct FloorGridOptions {
  double spacing_m = 0.1;  // reference: 0.1 m
  double margin_m = 0.5;   // beyond the train mics' bounding box (reference: 0.5 m)
  double height_m = std::numeric_limits<double>::quiet_NaN();  // mic height (y); NaN = the
                                                               // middle of the train mics' heights
  int64_t max_points = 4000;  // coarser spacing when the grid would have more points than this
};

// Positions of a regular grid over the floor (x right, z down in the picture; y = height).
struct FloorGrid {
  std::vector<double> x;  // [nx] ascending
  std::vector<double> z;  // [nz] ascending
  double height = 0;
  double spacing = 0;  // actually used (≥ options.spacing_m)
  int64_t size() const { return int64_t(x.size() * z.size()); }
  // [nz·nx, 3] float64 (x, height, z), row-major over (z, x).
  torch::Tensor positions() const;
};

// The grid over the train mics' box (the audio aabb shrunk by the 1 m NeRAF adds) widened by the
// margin, so every point stays strictly inside the aabb when margin < 1 m: x from min − margin in
// `spacing` steps while ≤ max + margin (np.arange up to and including the end up to rounding).
// The height defaults to the box's middle (= the train mics' height when they all share one).
// Throws neraf::Error for a non-positive spacing or a height outside the aabb.
FloorGrid make_floor_grid(const data::Aabb& audio_aabb, const FloorGridOptions& options = {});

// Per-frame RMS of a linear magnitude spectrogram, librosa.feature.rms(S=mag, frame_length=n_fft)
// with n_fft = 2(F − 1): sqrt(2·Σ_f w_f·mag² / n_fft²), w = 1/2 at DC and Nyquist, else 1.
// mag: [..., F, T] → [..., T].
torch::Tensor spectrogram_rms(const torch::Tensor& magnitude);

// log(Σ_t rms_t) of channel 0 of clip(exp(log_stft) − 1e-3, 0, 1e4). log_stft: [N, C, F, T] → [N]
// float64 (−inf for a silent prediction).
torch::Tensor log_loudness(const torch::Tensor& log_stft);

struct LoudnessMap {
  FloorGrid grid;
  geometry::Vec3 source;
  double yaw_deg = 0;
  torch::Tensor values;  // [nz, nx] float64 log loudness
};

// Predicts every grid position (batches of `poses_per_batch` poses) and computes the map.
LoudnessMap compute_loudness_map(const LogStftFn& predict, const FloorGrid& grid,
                                 const geometry::Vec3& source, double yaw_deg,
                                 int64_t poses_per_batch = 64, bool progress = true);

// The map as a PNG heat map: one block of pixels per grid cell (viridis, min → max of the finite
// values), x to the right and z downwards (a top view, y up), tick marks with metre labels, the
// source as a white ring (when inside the grid), and a colour bar with its min/max values.
void write_loudness_png(const std::string& path, const LoudnessMap& map);

// "x_m,y_m,z_m,log_loudness" rows (row-major over z, then x), written atomically.
void write_loudness_csv(const std::string& path, const LoudnessMap& map);

// PATH with its extension replaced by ".csv" ("map.png" → "map.csv", "map" → "map.csv").
std::string csv_path_for(const std::string& png_path);

}  // namespace neraf::render
