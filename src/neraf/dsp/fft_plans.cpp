#include "neraf/dsp/fft_plans.h"

#include <cstring>
#include <map>
#include <mutex>
#include <new>
#include <utility>

namespace neraf::dsp::detail {

AlignedFloats alloc_floats(size_t n) {
  float* p = fftwf_alloc_real(n == 0 ? 1 : n);
  if (!p) throw std::bad_alloc();
  std::memset(p, 0, (n == 0 ? 1 : n) * sizeof(float));
  return AlignedFloats(p);
}

namespace {

// Why a process-wide cache: FFTW's planner is not thread-safe (its own planner state is global),
// so creating plans must be serialised anyway, and creating one costs far more than executing it
// (Griffin-Lim runs thousands of 1024-point transforms per call). Plans are immutable once made
// and are executed through the thread-safe new-array interface, so sharing them is safe. The cache
// only ever grows by one plan per (kind, size) actually used, and it never changes results:
// FFTW_ESTIMATE chooses the algorithm from the size alone (no timing), so the same size always gets
// the same plan and the same numbers, run after run (FFTW_MEASURE would not be deterministic).
class PlanCache {
 public:
  fftwf_plan get(FftKind kind, int n) {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto key = std::make_pair(static_cast<int>(kind), n);
    auto it = plans_.find(key);
    if (it != plans_.end()) return it->second;
    fftwf_plan plan = make(kind, n);
    if (!plan) throw std::bad_alloc();  // FFTW only fails to plan when out of memory
    plans_.emplace(key, plan);
    return plan;
  }

 private:
  static fftwf_plan make(FftKind kind, int n) {
    const size_t nc = size_t(n) / 2 + 1;
    // Plan on aligned scratch arrays: the plan then expects (and gets) aligned arrays at execution.
    AlignedFloats a = alloc_floats(2 * nc);
    AlignedFloats b = alloc_floats(2 * nc);
    const unsigned flags = FFTW_ESTIMATE;
    switch (kind) {
      case FftKind::r2c_inplace:
        return fftwf_plan_dft_r2c_1d(n, a.get(), reinterpret_cast<fftwf_complex*>(a.get()), flags);
      case FftKind::c2r_inplace:
        return fftwf_plan_dft_c2r_1d(n, reinterpret_cast<fftwf_complex*>(a.get()), a.get(), flags);
      case FftKind::r2c:
        return fftwf_plan_dft_r2c_1d(n, a.get(), reinterpret_cast<fftwf_complex*>(b.get()), flags);
      case FftKind::c2r:
        return fftwf_plan_dft_c2r_1d(n, reinterpret_cast<fftwf_complex*>(a.get()), b.get(), flags);
    }
    return nullptr;
  }

  std::mutex mutex_;
  std::map<std::pair<int, int>, fftwf_plan> plans_;
};

PlanCache& plan_cache() {
  // Never destroyed, not even at exit: a thread still transforming while the process exits never
  // meets a freed plan, and the plans stay reachable (no leak report from LeakSanitizer, which
  // flagged them when a static cache's map was destroyed at exit without them).
  static PlanCache* const cache = new PlanCache;
  return *cache;
}

}  // namespace

fftwf_plan fft_plan(FftKind kind, int n) { return plan_cache().get(kind, n); }

}  // namespace neraf::dsp::detail
