#pragma once
// Auralization: dry (anechoic) audio convolved with a room impulse response, and the peak
// normalisation that usually follows. Used by `neraf auralize` (file mode and model mode).
#include "neraf/io/audio_file.h"

namespace neraf::dsp {

// Output channel count of auralize() for these inputs, or 0 when they cannot be combined:
//   dry 1 ch × RIR N ch -> N (each RIR channel applied to the dry signal; e.g. binaural)
//   dry N ch × RIR N ch -> N (channel by channel)
//   dry N ch × RIR 1 ch -> N (every dry channel through the same RIR)
int auralized_channels(int rir_channels, int dry_channels);

// Convolves `dry` with `rir` (FFT convolution, channels in parallel). Both must have the same
// sample rate (resample the dry audio first) and compatible channel counts (see above); otherwise
// throws neraf::Error. Output: rir's sample rate, num_frames = dry + rir − 1, not normalised.
io::AudioBuffer auralize(const io::AudioBuffer& rir, const io::AudioBuffer& dry);

// Largest |sample| over all channels (0 for silence).
float peak_abs(const io::AudioBuffer& audio);

// Scales every channel by the same gain so the peak becomes `target` (keeps the balance between
// channels, e.g. the interaural level difference). Silence is left unchanged. Returns the gain.
float normalize_peak(io::AudioBuffer& audio, float target = 0.99f);

}  // namespace neraf::dsp
