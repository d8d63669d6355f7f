#!/usr/bin/env bash
# Configures and builds neraf (Release, Ninja, -j2) into build/. Extra arguments go to the build
# step, e.g. `scripts/build.sh --target neraf`.
set -euo pipefail
cd "$(dirname "$0")/.."
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
if [ ! -f build/CMakeCache.txt ]; then
  cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release
else
  cmake -S . -B build >/dev/null
fi
cmake --build build -j2 "$@"
