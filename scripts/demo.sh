#!/usr/bin/env bash
# The README's main command: the whole neraf story on the built-in demo scene.
# Installs the Debian packages, builds, then runs each step into demo-out/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh --target neraf
NERAF=build/neraf
OUT=${NERAF_DEMO_OUT:-demo-out}
mkdir -p "$OUT"

echo "== metrics of a real measured binaural RIR (assets/real/brir_clap.wav)"
$NERAF metrics --rir assets/real/brir_clap.wav
echo "== auralize dry castanets with it"
$NERAF auralize --rir assets/real/brir_clap.wav --in assets/real/castanets_dry.wav \
  --out "$OUT/castanets_in_seminar_room.wav" --normalize
echo "demo outputs in $OUT/"
