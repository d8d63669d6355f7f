#pragma once
// MODEL.nrf: an exported acoustic field (NAcF with the scene feature folded in, its energy
// calibration and audio configuration), the file neraf_rt loads. Torch-free: `neraf export` fills
// a ModelData and calls write_model_file; the runtime calls read_model_file.
//
// File layout (all integers little-endian):
//   offset 0   magic "NERAFMDL"                      8 bytes
//          8   format version (kModelFormatVersion)  uint32
//         12   flags (bit 0: weights in bfloat16)    uint32
//         16   payload size P                        uint64
//         24   payload                               P bytes
//     24 + P   FNV-1a 64 of the payload bytes        uint64   (file size = 32 + P)
// Payload:
//   header size H (uint64), then H bytes of JSON text with every scalar field of ModelData (names
//   as below; "metadata" holds metadata_json as a string) and the shapes ("trunk" and "heads":
//   [[out, in], ...], "calibration": [C, F, T] or []), then the arrays back to back, in order:
//   for each trunk layer, then each head: weight [out, in] (float32, or bfloat16 with flag bit 0),
//   bias [out] (float32); then the calibration [C, F, T] (float32) if any. Biases stay float32 in
//   every precision: the scene feature is folded into trunk[0].bias.
// bfloat16: round-to-nearest-even of the float32 weights; read back widened to float32 (so a
// bf16 file's ModelData holds the rounded values, and the engine computes in float32 with them).
//
// Readers of format 1 ignore unknown header keys (a later writer may add optional fields without
// a new version) but refuse a key given twice; any change a format-1 reader would misread bumps
// kModelFormatVersion.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "neraf/neraf_rt.h"

namespace neraf::rt {

// What write_model_file writes: 1, or 2 for a file whose time encoding spans more frames than it
// predicts (time_frames), which a reader of version 1 would encode wrongly.
constexpr uint32_t kModelFormatVersion = 2;
constexpr uint32_t kModelFlagBf16 = 1u << 0;  // weights stored as bfloat16

// Input widths of the canonical NAcF input [time, mic, source, rot, relative geometry].
constexpr int64_t kTimeDim = 21;
constexpr int64_t kPositionDim = 63;
constexpr int64_t kRotDim = 16;
constexpr int64_t kRelativeGeometryDim = 22;
constexpr int64_t kPoseInputDim = kTimeDim + 2 * kPositionDim + kRotDim;  // 163

struct DenseLayer {
  int64_t in = 0, out = 0;
  std::vector<float> weight;  // [out, in] row-major
  std::vector<float> bias;    // [out]
};

struct ModelData {
  std::string neraf_version;  // the neraf that wrote the file, e.g. "0.1.0" (at most 31 bytes)
  int layout = 0;             // 0 soundspaces, 1 raf
  int sample_rate = 22050, channels = 2, n_fft = 512, win_length = 512, hop_length = 128;
  int n_freq = 257, max_len = 78;  // F, T
  // The frames the time encoding spans, when more than the T predicted (a scene of a multi-scene
  // run, at its own length of the run's longest); 0 = max_len.
  int time_frames = 0;
  int64_t waveform_length = 0;  // samples per channel of a rendered RIR; 0 → hop·(T−1)
  std::array<double, 3> box_min{}, box_max{};  // the audio aabb used to normalise positions

  // NAcF. Inputs in one canonical order, the scene feature already folded into trunk[0].bias:
  //   [time (21), mic (63), source (63), rot (16), relative geometry (22, if relative_geometry)]
  bool relative_geometry = false;
  double position_max_freq_exp = 8.0;       // mic/source NeRF encoding's highest exponent
  std::array<double, 3> extent_m{1, 1, 1};  // for the relative geometry (metres)
  double leaky_slope = 0.1, output_scale = 10.0;
  std::vector<DenseLayer> trunk;   // LeakyReLU after each
  std::vector<DenseLayer> heads;   // one per channel, [F, W]; out = output_scale·tanh(.)
  std::vector<float> calibration;  // [C, F, T] energy gains, or empty

  bool bf16_storage = false;  // write the weights as bfloat16 (export --precision bf16)
  std::string metadata_json;  // free-form JSON text (frames, data manifest, training summary)

  // The canonical input width trunk[0] must take: 163, or 185 with relative_geometry.
  int64_t input_dim() const {
    return kPoseInputDim + (relative_geometry ? kRelativeGeometryDim : 0);
  }
  // Samples per channel of a rendered RIR (waveform_length, or hop·(T−1) when 0).
  int64_t rir_length() const {
    return waveform_length > 0 ? waveform_length : int64_t(hop_length) * (max_len - 1);
  }
};

// What read_model_file / parse_model / check_model_data throw: a status of neraf_rt.h
// (NERAF_ERR_IO, NERAF_ERR_FORMAT, NERAF_ERR_VERSION) and a one-line message naming the file.
// The format a file of `m` is written in (1, or 2 when it needs time_frames).
inline uint32_t format_version_of(const ModelData& m) {
  return m.time_frames > 0 && m.time_frames != m.max_len ? 2u : 1u;
}

class ModelFileError : public std::runtime_error {
 public:
  ModelFileError(neraf_status status, const std::string& message)
      : std::runtime_error(message), status_(status) {}
  neraf_status status() const { return status_; }

 private:
  neraf_status status_;
};

// Writes `m` to `path` atomically (a temporary file in the same folder, fsync, rename): either the
// complete new file or the previous state. Throws std::runtime_error (a ModelFileError for an
// invalid ModelData) with a one-line message naming the file.
void write_model_file(const std::string& path, const ModelData& m);

// The bytes write_model_file writes (for tests and for writing elsewhere than a file).
std::vector<uint8_t> serialize_model(const ModelData& m, const std::string& name = "model");

// Reads and fully validates a model file (see check_model_data). Throws ModelFileError.
ModelData read_model_file(const std::string& path);

// Parses the bytes of a model file; `name` (the file) starts every error message. Never reads
// outside [data, data + size), allocates no more than the bytes justify, and throws only
// ModelFileError (or std::bad_alloc) for any input: a fuzz entry point.
ModelData parse_model(const uint8_t* data, size_t size, const std::string& name);

// Throws ModelFileError(NERAF_ERR_FORMAT, "<name>: ...") unless `m` is a model the runtime can
// run: sane sizes and STFT parameters, consistent shapes and layer chaining, array lengths that
// match them, finite values; plausible ones (sample rate 8000..384000 Hz, output_scale in
// (0, 30], leaky_slope in [0, 1], a box within ±10 km and an extent at least 1 mm wide on every
// axis, a mono raf layout); metadata_json empty or JSON without a key given twice, agreeing with
// the header where it holds the run's audio manifest ("data"."audio", what export writes).
void check_model_data(const ModelData& m, const std::string& name);

// bfloat16 conversion (round to nearest, ties to even; finite inputs) and back (exact). Inline:
// the AMX path converts every activation with it.
inline uint16_t float_to_bf16(float x) {
  uint32_t u;
  std::memcpy(&u, &x, 4);
  u += 0x7FFFu + ((u >> 16) & 1u);
  return uint16_t(u >> 16);
}
inline float bf16_to_float(uint16_t h) {
  const uint32_t u = uint32_t(h) << 16;
  float x;
  std::memcpy(&x, &u, 4);
  return x;
}

// FNV-1a 64 of `size` bytes (the file's checksum).
uint64_t fnv1a64(const uint8_t* data, size_t size);

}  // namespace neraf::rt
