#!/usr/bin/env bash
# P10 SILENT: synth --hrtf is ignored (not even read) with --layout raf.
source "$(dirname "$0")/setup.sh"
: > empty.sofa; rm -rf rafh
$N synth --scene tiny.json --layout raf --hrtf empty.sofa --out rafh --quiet; echo "rc=$?"
