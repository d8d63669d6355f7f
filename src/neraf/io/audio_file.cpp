#include "neraf/io/audio_file.h"

#include <sndfile.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::io {
namespace {

// Owns an SNDFILE* so every early return / throw closes the file.
struct SndCloser {
  void operator()(SNDFILE* f) const {
    if (f) sf_close(f);
  }
};
using SndHandle = std::unique_ptr<SNDFILE, SndCloser>;

// Frames moved per libsndfile call: bounds the interleaved scratch buffer for long files.
constexpr sf_count_t kChunkFrames = 1 << 16;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// libsndfile opens a WAV/AIFF whose data chunk is cut short (an interrupted copy or recording)
// and silently returns only the frames present; it only notes "data : <declared> (should be
// <actual>)" in its log. A declared size larger than what is there means the file was truncated.
// 0 and the sizes writers put when they cannot seek back (0xFFFFFFFF and a few bytes less,
// 0x7FFFFFFF, and 0x7FFFF000 of `espeak-ng --stdout` / SoX to a pipe) are placeholders of
// streamed audio, not truncation.
bool streamed_size_placeholder(long long declared) {
  return declared >= 0xFFFFFF00LL || declared == 0x7FFFFFFFLL || declared == 0x7FFFF000LL;
}

bool data_chunk_truncated(SNDFILE* file, int64_t* declared, int64_t* actual) {
  std::string log(1 << 14, '\0');
  sf_command(file, SFC_GET_LOG_INFO, log.data(), static_cast<int>(log.size()));
  for (size_t pos = log.find("data :"); pos != std::string::npos;
       pos = log.find("data :", pos + 1)) {
    const size_t eol = log.find('\n', pos);
    const std::string line =
        log.substr(pos, eol == std::string::npos ? std::string::npos : eol - pos);
    long long d = 0, a = 0;
    if (std::sscanf(line.c_str(), "data : %lld (should be %lld)", &d, &a) == 2 && d > a && d > 0 &&
        !streamed_size_placeholder(d)) {
      *declared = d;
      *actual = a;
      return true;
    }
  }
  return false;
}

}  // namespace

namespace {

// Opens `path` with the checks every reader shares; `info` gets the header.
SndHandle open_checked(const std::string& path, SF_INFO& info, uintmax_t& bytes, bool& size_known) {
  std::error_code ec;
  require(fs::exists(path, ec), path + ": no such file; check the path");
  require(!fs::is_directory(path, ec), path + ": is a folder, expected an audio file");
  // A FIFO or device would block the reader (or never end); datasets and inputs are files.
  require(fs::is_regular_file(path, ec),
          path + ": is not a regular file (a pipe or device?); pass an audio file");
  bytes = fs::file_size(path, ec);
  size_known = !ec;
  require(!size_known || bytes > 0,
          path + ": the file is empty (0 bytes); expected an audio file (WAV, FLAC, ...)");
  // libsndfile reports an unreadable file as a format error.
  if (std::FILE* probe = std::fopen(path.c_str(), "rb"))
    std::fclose(probe);
  else
    throw Error(path + ": cannot open (" + std::strerror(errno) + "); check its permissions");
  info = SF_INFO{};
  SndHandle file(sf_open(path.c_str(), SFM_READ, &info));
  if (!file) {
    // sf_strerror(nullptr) reports why the last sf_open failed (unknown format, truncated
    // header, permission denied...).
    throw Error(path + ": not an audio file libsndfile can read (" + sf_strerror(nullptr) +
                "); expected WAV, FLAC or another libsndfile format");
  }
  require(info.channels > 0, path + ": the audio file declares no channels; re-export it");
  require(info.samplerate > 0, path + ": the audio file declares no sample rate; re-export it");
  int64_t declared = 0, actual = 0;
  if (data_chunk_truncated(file.get(), &declared, &actual)) {
    throw Error(path + ": truncated audio file (its header announces " + std::to_string(declared) +
                " bytes of samples, only " + std::to_string(actual) +
                " are there); re-export or re-copy it");
  }
  return file;
}

}  // namespace

AudioFileInfo read_audio_info(const std::string& path) {
  SF_INFO info{};
  uintmax_t bytes = 0;
  bool size_known = false;
  const SndHandle file = open_checked(path, info, bytes, size_known);
  AudioFileInfo out;
  out.sample_rate = info.samplerate;
  out.channels = info.channels;
  out.frames = info.frames == SF_COUNT_MAX ? -1 : static_cast<int64_t>(info.frames);
  return out;
}

AudioBuffer read_audio(const std::string& path) {
  SF_INFO info{};
  uintmax_t bytes = 0;
  bool size_known = false;
  SndHandle file = open_checked(path, info, bytes, size_known);
  require(info.frames > 0, path + ": the audio file is empty (0 frames); expected a recording");

  // Float files are returned as stored; integer files are scaled to [-1, 1) by libsndfile (its
  // default normalisation).
  AudioBuffer out;
  out.sample_rate = info.samplerate;
  const int nc = info.channels;
  // The header's frame count is a claim, not a size to allocate: libsndfile reports SF_COUNT_MAX
  // for a stream of unknown length (e.g. an Ogg file without its last page), and a damaged header
  // can announce billions of frames. Reserve at most one frame per byte of the file (what nearly
  // every real file needs at most) and grow with what is actually decoded.
  const bool length_known = info.frames != SF_COUNT_MAX;
  const sf_count_t size_bound =
      size_known ? static_cast<sf_count_t>(std::min<uintmax_t>(bytes, uintmax_t(1) << 40))
                 : kChunkFrames;
  const sf_count_t reserve = std::min(info.frames, std::max(kChunkFrames, size_bound));
  out.channels.assign(nc, {});
  for (auto& ch : out.channels) ch.reserve(static_cast<size_t>(reserve));

  std::vector<float> interleaved(static_cast<size_t>(std::min(info.frames, kChunkFrames)) * nc);
  sf_count_t done = 0;
  while (!length_known || done < info.frames) {
    const sf_count_t want =
        length_known ? std::min(kChunkFrames, info.frames - done) : kChunkFrames;
    const sf_count_t got = sf_readf_float(file.get(), interleaved.data(), want);
    if (got <= 0) break;
    for (sf_count_t i = 0; i < got * nc; ++i) {
      // Checked here, once for every reader: a NaN or 1e30 sample poisons every STFT, metric and
      // convolution computed from the file, far from where it came in.
      const float v = interleaved[size_t(i)];
      if (!std::isfinite(v) || std::abs(v) > kMaxAbsSample) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%g", static_cast<double>(v));
        throw Error(path + ": sample " + std::to_string(done + i / nc) + " of channel " +
                    std::to_string(i % nc) + " is " + buf +
                    (std::isfinite(v) ? " (beyond ±1000, +60 dB over full scale)" : "") +
                    "; the file is damaged, re-export it");
      }
    }
    for (int c = 0; c < nc; ++c) {
      std::vector<float>& ch = out.channels[c];
      for (sf_count_t i = 0; i < got; ++i) ch.push_back(interleaved[size_t(i) * nc + c]);
    }
    done += got;
  }
  require(length_known || done > 0,
          path + ": the audio file is empty (0 frames could be read); expected a recording");
  if (length_known && done < info.frames) {
    throw Error(path + ": truncated audio file (header announces " + std::to_string(info.frames) +
                " frames, only " + std::to_string(done) +
                " could be read); re-export or re-copy it");
  }
  return out;
}

void write_audio(const std::string& path, const AudioBuffer& audio, AudioFormat format) {
  require(audio.num_channels() > 0, path + ": nothing to write (no audio channels)");
  require(audio.sample_rate > 0, path + ": cannot write audio with sample rate " +
                                     std::to_string(audio.sample_rate) +
                                     " Hz; it must be positive");
  const size_t n = audio.channels[0].size();
  for (const auto& ch : audio.channels) {
    require(ch.size() == n, path + ": all audio channels must have the same length to be written");
    // A NaN/Inf sample would be written silently and poison every later computation on the file.
    for (float v : ch) {
      if (!std::isfinite(v)) {
        throw Error(path + ": refusing to write audio containing NaN or infinite samples");
      }
    }
  }

  if (format == AudioFormat::from_extension) {
    const std::string ext = lower_extension(path);
    // Anything else would be a WAV under a misleading name (an ".mp3" that is not MP3).
    require(ext.empty() || ext == ".wav" || ext == ".flac",
            path + ": neraf writes WAV (.wav) or FLAC (.flac) files, not " + ext +
                "; change the file's extension");
    format = ext == ".flac" ? AudioFormat::flac_pcm24 : AudioFormat::wav_float;
  }
  int sf_format = 0;
  switch (format) {
    case AudioFormat::wav_float:
      sf_format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
      break;
    case AudioFormat::wav_pcm16:
      sf_format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
      break;
    case AudioFormat::flac_pcm24:
      sf_format = SF_FORMAT_FLAC | SF_FORMAT_PCM_24;
      require(audio.num_channels() <= 8, path + ": FLAC holds at most 8 channels; write " +
                                             std::to_string(audio.num_channels()) +
                                             " channels as WAV instead");
      break;
    case AudioFormat::from_extension:
      break;  // resolved above
  }

  const int nc = audio.num_channels();
  write_atomically(path, [&](const std::string& tmp) {
    SF_INFO info{};
    info.samplerate = audio.sample_rate;
    info.channels = nc;
    info.format = sf_format;
    require(sf_format_check(&info) != 0, path + ": libsndfile cannot store " + std::to_string(nc) +
                                             " channels at " + std::to_string(audio.sample_rate) +
                                             " Hz in this format; choose WAV");
    SndHandle file(sf_open(tmp.c_str(), SFM_WRITE, &info));
    if (!file) {
      throw Error(path + ": cannot open for writing (" + sf_strerror(nullptr) +
                  "); choose a writable output path");
    }
    // Integer formats: clip out-of-range samples instead of letting them wrap around.
    sf_command(file.get(), SFC_SET_CLIPPING, nullptr, SF_TRUE);
    // No PEAK chunk: it holds a time stamp, and the same samples must give the same bytes.
    sf_command(file.get(), SFC_SET_ADD_PEAK_CHUNK, nullptr, SF_FALSE);

    std::vector<float> interleaved(std::min<size_t>(n, kChunkFrames) * nc);
    size_t done = 0;
    while (done < n) {
      const size_t count = std::min<size_t>(kChunkFrames, n - done);
      for (size_t i = 0; i < count; ++i) {
        for (int c = 0; c < nc; ++c) interleaved[i * nc + c] = audio.channels[c][done + i];
      }
      const sf_count_t wrote = sf_writef_float(file.get(), interleaved.data(), sf_count_t(count));
      if (wrote != sf_count_t(count)) {
        throw Error(path + ": write failed (" + sf_strerror(file.get()) +
                    "); free disk space and retry");
      }
      done += count;
    }
    // Close before the rename so the header is complete on disk.
    const int rc = sf_close(file.release());
    require(rc == 0, path + ": could not finish writing the file (" + sf_error_number(rc) +
                         "); free disk space and retry");
  });
}

}  // namespace neraf::io
