#!/usr/bin/env bash
# P03 LEFTOVER: render trajectory writes --out, then fails on --frames (exit 1) and leaves the WAV.
source "$(dirname "$0")/setup.sh"
rm -f t1.wav t2.wav; echo x > afile.txt
$N render trajectory --run run --path path.json --in dry.wav --frames t1.wav --out t1.wav; echo "rc=$?"; ls -la t1.wav
$N render trajectory --run run --path path.json --in dry.wav --frames /proc/x --out t2.wav; echo "rc=$?"; ls -la t2.wav
