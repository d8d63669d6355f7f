#pragma once
// The heap settings of every neraf program (the CLI and the benchmarks, so their timings match).

namespace neraf::util {

// Keeps freed memory in the heap instead of unmapping it: large per-step tensors would otherwise go
// through mmap/munmap every step and page-fault each time (measured ~2× faster training steps on 2
// cores). Call once at the start of main.
void keep_freed_memory_in_heap();

}  // namespace neraf::util
