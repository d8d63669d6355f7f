#!/usr/bin/env bash
# P18 UNCLEAR: disk-full errors name the hidden temp path (and export gives no fix).
source "$(dirname "$0")/setup.sh"
mkdir -p full; mountpoint -q full || mount -t tmpfs -o size=200k tmpfs full
$N export --run run --out full/m.nrf; echo "rc=$?"
$N synth --scene tiny.json --out full/ds --quiet; echo "rc=$?"
dd if=/dev/zero of=full/filler bs=1k count=190 2>/dev/null
$N eval --run run --json full/e.json --images full/img --max-views 1 --no-baselines --quiet; echo "rc=$?"
rm -f full/filler; umount full
