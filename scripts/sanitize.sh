#!/usr/bin/env bash
# The sanitizer build of the test suite's LibTorch-free part: util, io (WAV/FLAC, PNG, .npy, JSON,
# atomic and sealed files, the folder lock), dsp, metrics, geometry (paths, pose lists) and the
# runtime with its C API and streaming convolver, built with AddressSanitizer + UndefinedBehavior-
# Sanitizer (GCC) into build-asan/ and run; any report fails its test (UBSan does not recover).
# The LibTorch stages are left out to keep CI within its time: built again instrumented they
# would add about 15 minutes on 2 cores (docs/ARCHITECTURE.md, "Sanitizers").
#   scripts/sanitize.sh            build and run the subset
#   scripts/sanitize.sh -R Wav     any ctest arguments are passed through
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build=build-asan
flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=8 \
    -DNERAF_WITH_TORCH=OFF -DNERAF_BENCH=OFF -DNERAF_TESTS=ON \
    -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
fi
cmake --build "$build" -j2
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
cd "$build"
# runtime_install builds an uninstrumented example against the instrumented library: left out.
ctest --output-on-failure -j2 --timeout 900 -E '^runtime_install$' "$@"
