#include "neraf/data/audio_probe.h"

#include <sndfile.h>
#include <sys/stat.h>

namespace neraf::data {

AudioProbe probe_audio(const std::string& path) {
  AudioProbe p;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    p.error = "no such file";
    return p;
  }
  if (S_ISDIR(st.st_mode)) {
    p.error = "is a folder, not an audio file";
    return p;
  }
  if (st.st_size == 0) {
    p.error = "the file is empty (0 bytes)";
    return p;
  }
  SF_INFO info{};
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, &info);
  if (!f) {
    p.error = std::string("not a readable audio file (") + sf_strerror(nullptr) + ")";
    return p;
  }
  sf_close(f);
  p.ok = true;
  p.sample_rate = info.samplerate;
  p.channels = info.channels;
  p.frames = static_cast<int64_t>(info.frames);
  return p;
}

}  // namespace neraf::data
