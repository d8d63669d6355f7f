#!/usr/bin/env bash
# The README's test command: installs the Debian packages, builds everything from scratch if
# needed, and runs the whole test suite (CTest labels `fast` and `slow`).
#   scripts/test.sh            all tests
#   scripts/test.sh -L fast    only the fast ones (any ctest arguments are passed through)
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
cd build
ctest --output-on-failure -j2 --timeout 900 "$@"
