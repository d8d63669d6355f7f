#include "neraf/runtime/fftw_planner.h"

namespace neraf::rt {

std::mutex& fftw_planner_mutex() {
  static std::mutex mutex;  // a function-local static: usable from other statics' constructors
  return mutex;
}

}  // namespace neraf::rt
