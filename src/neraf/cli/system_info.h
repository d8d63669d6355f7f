#pragma once
#include <string>

namespace neraf::cli {

// LibTorch and OpenBLAS share libgomp's thread pool, whose idle threads spin for 300,000 turns
// before they sleep unless told otherwise; two neraf processes using all cores each then hold the
// cores the other needs (measured: docs/BENCHMARKS.md, bench/omp_contention.sh). libgomp reads
// its settings when it is loaded, before main, so this runs the program again (same PID,
// arguments and output) with GOMP_SPINCOUNT=1000, unless the user set GOMP_SPINCOUNT or
// OMP_WAIT_POLICY. Returns only when it did not run it again.
void run_again_with_short_openmp_spin(char** argv);

// The path of this program's binary (/proc/self/exe resolved), "" when it cannot be read. Exec it
// rather than /proc/self/exe, which would name the new process "exe" in ps, top and pkill.
std::string own_executable();

// How libgomp's idle threads wait, as the environment sets it ("GOMP_SPINCOUNT=1000", or
// "libgomp default" when neither variable is set).
std::string openmp_wait_text();

// LibTorch 1.13 from Debian starts with one intra-op thread; use every core the process may run
// on unless OMP_NUM_THREADS gives a count --threads would accept (another value is ignored with a
// warning; `--threads` options still override this later).
void use_all_cores();

// "neraf 0.1.0" plus LibTorch version, thread count, OpenMP wait and the BLAS library actually
// loaded.
std::string version_text();

// Path of the BLAS shared library mapped into this process after a matrix product, read from
// /proc/self/maps (empty if none is found). LibTorch's products are ~16× slower without
// OpenBLAS's OpenMP build, so `neraf --version` reports which one is really in use.
std::string loaded_blas_library();

}  // namespace neraf::cli
