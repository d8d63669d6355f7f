// io::read_audio on arbitrary bytes: libsndfile's readers (WAV, FLAC, AIFF, AU, ... it picks the
// format from the content) and neraf's own checks around them (empty, truncated, no channels).
// read_audio promises a neraf::Error for every file it cannot read; anything else is a finding.
#include <cstddef>
#include <cstdint>

#include "common.h"
#include "neraf/io/audio_file.h"
#include "neraf/util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // ".wav": libsndfile detects the format from the header, so the extension only matters for the
  // few headerless formats it guesses from the name.
  const std::string path = neraf::fuzz::write_input(data, size, ".wav");
  try {
    const neraf::io::AudioBuffer a = neraf::io::read_audio(path);
    // What the header promises of a file that was read: samples, a rate, planar equal channels.
    NERAF_FUZZ_CHECK(a.sample_rate > 0);
    NERAF_FUZZ_CHECK(a.num_channels() > 0);
    NERAF_FUZZ_CHECK(a.num_frames() > 0);
    for (const auto& ch : a.channels) NERAF_FUZZ_CHECK(ch.size() == a.channels[0].size());
  } catch (const neraf::Error&) {
    // The documented outcome for a bad file.
  }
  return 0;
}
