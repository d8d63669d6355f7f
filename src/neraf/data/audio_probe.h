#pragma once
// Cheap checks of audio files: the header only (sample rate, channels, length), through
// io::read_audio_info, without reading the samples. Used to validate tens of thousands of RIRs
// quickly; the same header checks as every sample reader (truncation included).
#include <cstdint>
#include <string>

namespace neraf::data {

struct AudioProbe {
  bool ok = false;    // a readable audio header
  std::string error;  // why not (when !ok), without the path: "no such file; check the path", ...
  int sample_rate = 0;
  int channels = 0;
  int64_t frames = 0;  // 0 for a header-only (empty) file

  double duration_s() const { return sample_rate > 0 ? double(frames) / sample_rate : 0.0; }
};

AudioProbe probe_audio(const std::string& path);

// An Error's message without the leading "<path>: " (io errors name their file; a Problem names
// it separately).
std::string strip_path(const std::string& message, const std::string& path);

}  // namespace neraf::data
