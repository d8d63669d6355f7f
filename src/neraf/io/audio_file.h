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
  int64_t num_frames() const {
    return channels.empty() ? 0 : static_cast<int64_t>(channels[0].size());
  }
  double duration_s() const { return sample_rate > 0 ? double(num_frames()) / sample_rate : 0.0; }
};

// The largest |sample| read_audio accepts: +60 dB over full scale. No recording or simulation is
// that loud; a float file with such values (1e30, denormal garbage) is damaged, not audio.
constexpr float kMaxAbsSample = 1000.0f;

// What an audio file's header says, after the checks that need no samples.
struct AudioFileInfo {
  int sample_rate = 0;
  int channels = 0;
  int64_t frames = 0;  // 0 for a header-only file (SoundSpaces ships some); -1: unknown (a stream)
};

// Reads and checks the header only (cheap: used to check tens of thousands of RIRs). Throws
// neraf::Error naming the file for a missing file, a folder, a 0-byte or non-audio file, a header
// without channels or sample rate, and a WAV/AIFF whose data chunk is shorter than its header
// announces (a copy cut short). A header-only file (0 frames) is not an error here.
AudioFileInfo read_audio_info(const std::string& path);

// Reads a whole file: read_audio_info's checks, then every sample. Throws neraf::Error naming the
// file for an empty (0 frames) or truncated file (fewer frames than the header announces), and
// for NaN / infinite samples or samples beyond ±kMaxAbsSample. Every audio reader of neraf goes
// through here, so these checks hold for datasets, --rir, --dry and metrics inputs alike.
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
