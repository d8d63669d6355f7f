#pragma once
#include <string>

namespace neraf::cli {

// LibTorch 1.13 from Debian starts with one intra-op thread; use every core the process may run
// on unless OMP_NUM_THREADS gives a count --threads would accept (another value is ignored with a
// warning; `--threads` options still override this later).
void use_all_cores();

// "neraf 0.1.0" plus LibTorch version, thread count and the BLAS library actually loaded.
std::string version_text();

// Path of the BLAS shared library mapped into this process after a matrix product, read from
// /proc/self/maps (empty if none is found). LibTorch's products are ~16× slower without
// OpenBLAS's OpenMP build, so `neraf --version` reports which one is really in use.
std::string loaded_blas_library();

}  // namespace neraf::cli
