#!/usr/bin/env bash
# P12 SILENT: eval --novel-data = the run's own dataset: its 16 training RIRs are scored as "novel".
source "$(dirname "$0")/setup.sh"
$N eval --run run --novel-data ds --json z.json --skip-vision --no-images --no-baselines --quiet; echo "rc=$?"
python3 -c "import json; print('novel n_rirs', json.load(open('z.json'))['audio']['novel']['neraf']['n_rirs'])"
