#!/usr/bin/env bash
# P04 LEFTOVER: an --out with a trailing slash creates an empty folder, then blames it.
source "$(dirname "$0")/setup.sh"
rm -rf slash.wav
$N render rir --run run $MIC --out slash.wav/; echo "rc=$?"; ls -ld slash.wav
