#!/usr/bin/env bash
# Configures and builds neraf (Release, Ninja, -j2) into build/. Extra arguments go to the build
# step, e.g. `scripts/build.sh --target neraf`.
set -euo pipefail
cd "$(dirname "$0")/.."
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
if [ ! -f build/CMakeCache.txt ]; then
  # Unity build: each target's sources compiled 8 to a translation unit, so LibTorch's and CLI11's
  # header-only code is instantiated once per 8 files, not per file: a build from scratch took
  # 9 instead of 22 minutes on 2 cores (bench/results/build_time.json).
  cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON \
    -DCMAKE_UNITY_BUILD_BATCH_SIZE=8
else
  cmake -S . -B build >/dev/null
fi
cmake --build build -j2 "$@"
