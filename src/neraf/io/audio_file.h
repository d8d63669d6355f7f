#pragma once
// Audio files through libsndfile: WAV, FLAC and everything else it reads, any channel count,
// samples as float in [-1, 1] (integer formats are scaled by libsndfile).
#include <cstdint>
#include <string>
#include <vector>

namespace neraf::io {

struct AudioBuffer {
  int sample_rate = 0;
  std::vector<std::vector<float>> channels;  // [n_channels][n_frames], planar

  int num_channels() const { return static_cast<int>(channels.size()); }
  int64_t num_frames() const { return channels.empty() ? 0 : static_cast<int64_t>(channels[0].size()); }
  double duration_s() const { return sample_rate > 0 ? double(num_frames()) / sample_rate : 0.0; }
};

// Reads a whole file. Throws neraf::Error naming the file for a missing, empty (0 frames),
// truncated or non-audio file.
AudioBuffer read_audio(const std::string& path);

enum class AudioFormat {
  from_extension,  // .flac -> FLAC 24-bit, anything else -> WAV 32-bit float
  wav_float,
  wav_pcm16,
  flac_pcm24,
};

// Writes atomically (temp file + rename). All channels must have the same length.
void write_audio(const std::string& path, const AudioBuffer& audio,
                 AudioFormat format = AudioFormat::from_extension);

}  // namespace neraf::io
