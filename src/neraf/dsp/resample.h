#pragma once
// Sample-rate conversion with libsamplerate at its best quality (SRC_SINC_BEST_QUALITY).
// Output length round(n · to / from).
#include <vector>

#include "neraf/io/audio_file.h"

namespace neraf::dsp {

std::vector<float> resample(const std::vector<float>& x, double from_hz, double to_hz);
io::AudioBuffer resample(const io::AudioBuffer& audio, int to_hz);

}  // namespace neraf::dsp
