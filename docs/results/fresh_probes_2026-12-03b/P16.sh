#!/usr/bin/env bash
# P16 UNCLEAR: an audio run whose vision run moved: "VISION: no such run folder; check --run".
source "$(dirname "$0")/setup.sh"
rm -rf vrun arun; cp -r run vrun
$N train --modality audio --data ds --vision-run vrun --out arun --steps 2 --rays 128 --quiet >/dev/null 2>&1
mv vrun vrun_moved
$N eval --run arun --json a.json --no-images --no-baselines --quiet; echo "rc=$?"
mv vrun_moved vrun
