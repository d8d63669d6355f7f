#!/usr/bin/env bash
# P11 SILENT: audio-only flags accepted and ignored with --modality vision; --grid-resolution with --grid none.
source "$(dirname "$0")/setup.sh"
rm -rf C01 C02
$N train --data ds --modality vision --decay-loss 5 --audio-fraction 0.5 --out C01 --steps 2 --rays 128 --quiet; echo "rc=$?"
$N train --data ds --grid none --grid-resolution 64 --out C02 --steps 2 --audio-start-step 0 --rays 128 --quiet; echo "rc=$?"
