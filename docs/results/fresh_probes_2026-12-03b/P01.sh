#!/usr/bin/env bash
# P01 SILENT: outputs may overwrite the run's own DATASET files (only run-folder files are guarded).
source "$(dirname "$0")/setup.sh"
rm -rf victim vicrun; cp -r ds victim; rm -rf victim/.neraf_cache
$N train --data victim --out vicrun --steps 2 --audio-start-step 0 --rays 128 --quiet >/dev/null 2>&1
md5sum victim/transforms.json victim/metadata/points.txt victim/binaural_rirs/0/0_9.wav
$N eval --run vicrun --json victim/transforms.json --skip-vision --no-images --no-baselines --quiet; echo "eval rc=$?"
$N render loudness --run vicrun --src 1.5,1.2,1.3 --spacing 0.5 --out loud.png --csv victim/metadata/points.txt; echo "loudness rc=$?"
$N render rir --run vicrun $MIC --out victim/binaural_rirs/0/0_9.wav; echo "rir rc=$?"
md5sum victim/transforms.json victim/metadata/points.txt victim/binaural_rirs/0/0_9.wav
$N info victim --no-t60 | tail -1   # now broken
