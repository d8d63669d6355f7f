#!/usr/bin/env bash
# The installed runtime as an application sees it: `cmake --install` into a temporary prefix,
# then pkg-config and find_package(neraf) against that prefix, and examples/auralize_path built
# and run on a tiny random model.
#   install_test.sh BUILD_DIR SOURCE_DIR MAKE_TEST_MODEL
set -euo pipefail
build=$1
src=$2
make_model=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix="$tmp/prefix"
fail() { echo "install_test: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$prefix" > "$tmp/install.log" || fail "cmake --install failed"
[[ -f "$prefix/include/neraf/neraf_rt.h" ]] || fail "no include/neraf/neraf_rt.h"
lib=$(find "$prefix" -name 'libneraf_rt.so.*' -type f | head -1)
[[ -n "$lib" ]] || fail "no libneraf_rt.so"
[[ -n "$(find "$prefix" -name neraf-config.cmake)" ]] || fail "no neraf-config.cmake"
# Only the C API is exported.
others=$(nm -D --defined-only "$lib" | awk '{print $3}' | grep -v '^neraf_' || true)
[[ -z "$others" ]] || fail "libneraf_rt exports more than neraf_*: $others"

# pkg-config, relocated: a C program built from its flags alone.
pc_dir=$(dirname "$(find "$prefix" -name neraf_rt.pc | head -1)")
cat > "$tmp/hello.c" <<'C'
#include <neraf/neraf_rt.h>
#include <stdio.h>
int main(void) {
  neraf_model* m;
  neraf_status s = neraf_model_load("/nonexistent.nrf", &m);
  printf("%s: %s\n", neraf_status_string(s), neraf_last_error());
  return s == NERAF_ERR_IO ? 0 : 1;
}
C
flags=$(PKG_CONFIG_PATH="$pc_dir" pkg-config --cflags --libs neraf_rt) || fail "pkg-config failed"
# shellcheck disable=SC2086
cc -std=c99 -Wall -Werror "$tmp/hello.c" -o "$tmp/hello" $flags -Wl,-rpath,"$(dirname "$lib")" \
  || fail "a C program does not build with pkg-config's flags"
"$tmp/hello" > /dev/null || fail "the pkg-config program did not run"

# find_package(neraf): the example.
cmake -S "$src/examples/auralize_path" -B "$tmp/example" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release > "$tmp/configure.log" 2>&1 \
  || { cat "$tmp/configure.log"; fail "the example does not configure against the prefix"; }
cmake --build "$tmp/example" > "$tmp/build.log" 2>&1 \
  || { cat "$tmp/build.log"; fail "the example does not build"; }

# A 0.25 s dry signal at 22.05 kHz, 16-bit mono: a click every 1000 samples.
# (The inner printf writes \xNN escapes, the outer one turns them into bytes.)
le32() {
  printf "$(printf '\\x%02x\\x%02x\\x%02x\\x%02x' $(($1 & 255)) $((($1 >> 8) & 255)) \
    $((($1 >> 16) & 255)) $((($1 >> 24) & 255)))"
}
le16() { printf "$(printf '\\x%02x\\x%02x' $(($1 & 255)) $((($1 >> 8) & 255)))"; }
n=5512
{
  printf 'RIFF'; le32 $((36 + 2 * n)); printf 'WAVEfmt '; le32 16; le16 1; le16 1
  le32 22050; le32 44100; le16 2; le16 16; printf 'data'; le32 $((2 * n))
  for ((i = 0; i < n; i += 1000)); do
    le16 16000
    head -c $((2 * (n - i < 1000 ? n - i - 1 : 999))) /dev/zero
  done
} > "$tmp/dry.wav"

"$make_model" "$tmp/room.nrf" --channels 2 --relative-geometry || fail "no test model"
# The box is [-1, 3] x [0, 2.5] x [-2, 1.5] m.
"$tmp/example/auralize_path" "$tmp/room.nrf" "$tmp/dry.wav" "$tmp/wet.wav" \
  --source 2 1.5 1 --from 0 1.2 -0.5 --to 2.5 1.2 0.5 --yaw 90 --block 128 --update 1024 \
  || fail "auralize_path failed"
size=$(stat -c %s "$tmp/wet.wav")
rir=$((128 * 23))  # the tool's model: hop 128, 24 frames
expected=$((44 + 4 * 2 * (n + rir)))
[[ "$size" -eq "$expected" ]] || fail "wet.wav has $size bytes, expected $expected"
# Silence in, silence out would mean nothing was convolved: some sample must be non-zero.
[[ -n "$(tail -c +45 "$tmp/wet.wav" | tr -d '\000' | head -c 1)" ]] || fail "wet.wav is silent"

# A path leaving the box is refused with the runtime's message, exit status 1.
if "$tmp/example/auralize_path" "$tmp/room.nrf" "$tmp/dry.wav" "$tmp/bad.wav" \
  --source 2 1.5 1 --from 0 1.2 -0.5 --to 9 1.2 0.5 2> "$tmp/err.txt"; then
  fail "a path outside the box was accepted"
fi
grep -q "outside the training box" "$tmp/err.txt" || { cat "$tmp/err.txt"; fail "no box message"; }
echo "install_test: ok"
