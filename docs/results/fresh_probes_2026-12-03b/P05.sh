#!/usr/bin/env bash
# P05 UNCLEAR: an empty --out gives "error: : cannot write the file (Success)".
source "$(dirname "$0")/setup.sh"
$N render rir --run run $MIC --out ""; echo "rc=$?"
