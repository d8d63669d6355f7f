#!/usr/bin/env bash
# P06 SILENT: an empty value is taken as "flag not given".
source "$(dirname "$0")/setup.sh"
rm -rf Y08; $N synth --scene tiny.json --plan-only "" --out Y08 --quiet; echo "synth rc=$? (a whole dataset was synthesised)"; ls Y08 | head -3
$N render rir --run run --checkpoint "" $MIC --out k.wav; echo "render rc=$? (latest checkpoint used)"
