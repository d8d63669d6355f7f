#pragma once
// Cheap checks of audio files: the header only (sample rate, channels, length), through
// libsndfile, without reading the samples. Used to validate tens of thousands of RIRs quickly.
#include <cstdint>
#include <string>

namespace neraf::data {

struct AudioProbe {
  bool ok = false;    // a readable audio header
  std::string error;  // why not (when !ok): "no such file", libsndfile's reason, ...
  int sample_rate = 0;
  int channels = 0;
  int64_t frames = 0;  // 0 for a header-only (empty) file

  double duration_s() const { return sample_rate > 0 ? double(frames) / sample_rate : 0.0; }
};

AudioProbe probe_audio(const std::string& path);

}  // namespace neraf::data
