#pragma once
// FFTW's planner (plan creation and destruction) is not thread-safe: its state is global to the
// process. Every plan neraf_rt creates or destroys does so under this one mutex; executing plans
// on one's own arrays (fftwf_execute_dft_r2c etc.) is thread-safe and needs no lock. Internal to
// neraf_rt (neraf_dsp has its own lock for its plan cache: a program that plans through both
// libraries from different threads at the same time must serialise the two itself).
#include <mutex>

namespace neraf::rt {

std::mutex& fftw_planner_mutex();

}  // namespace neraf::rt
