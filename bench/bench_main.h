#pragma once
// The main of every benchmark program: the neraf program's heap settings, then Google Benchmark.
#include <benchmark/benchmark.h>

#include "neraf/util/heap.h"

namespace neraf::bench {

inline int run_benchmarks(int argc, char** argv) {
  util::keep_freed_memory_in_heap();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace neraf::bench
