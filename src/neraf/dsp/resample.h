#pragma once
// Sample-rate conversion with libsoxr at its "HQ" quality (SOXR_HQ, one call over the whole
// signal): what librosa 0.10's default `res_type="soxr_hq"` runs, so the SoundSpaces loaders
// resample 44.1 → 22.05 kHz as the published code does. Output length ceil(n · to / from), as
// librosa's fix_length after soxr.
#include <vector>

#include "neraf/io/audio_file.h"

namespace neraf::dsp {

std::vector<float> resample(const std::vector<float>& x, double from_hz, double to_hz);
io::AudioBuffer resample(const io::AudioBuffer& audio, int to_hz);

}  // namespace neraf::dsp
