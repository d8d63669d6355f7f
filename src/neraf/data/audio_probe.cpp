#include "neraf/data/audio_probe.h"

#include "neraf/io/audio_file.h"
#include "neraf/util/error.h"

namespace neraf::data {

std::string strip_path(const std::string& message, const std::string& path) {
  const std::string prefix = path + ": ";
  return message.compare(0, prefix.size(), prefix) == 0 ? message.substr(prefix.size()) : message;
}

AudioProbe probe_audio(const std::string& path) {
  AudioProbe p;
  try {
    const io::AudioFileInfo info = io::read_audio_info(path);
    // A stream of unknown length (no frame count in its header) is not what a dataset ships.
    if (info.frames < 0) {
      p.error = "the header gives no length (a streamed file); re-export it as WAV or FLAC";
      return p;
    }
    p.ok = true;
    p.sample_rate = info.sample_rate;
    p.channels = info.channels;
    p.frames = info.frames;
  } catch (const Error& e) {
    p.error = strip_path(e.what(), path);
  }
  return p;
}

}  // namespace neraf::data
