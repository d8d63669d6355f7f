#!/usr/bin/env bash
# P09 SILENT: synth --plan-only X.jpg writes PNG bytes (render view/loudness refuse .jpg).
source "$(dirname "$0")/setup.sh"
$N synth --scene tiny.json --plan-only plan.jpg; echo "rc=$?"; file plan.jpg
