#pragma once
// Linear convolution through the FFT (FFTW). Output length a.size() + b.size() − 1.
#include <vector>

namespace neraf::dsp {

std::vector<float> fft_convolve(const std::vector<float>& a, const std::vector<float>& b);

}  // namespace neraf::dsp
