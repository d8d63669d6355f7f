#!/bin/bash
# Weight averaging (`neraf train --audio-average F`) on the RAF-layout furnished room (issue 13's
# RAF target): experiment 2's full model (audio-only on a frozen vision run, cpu preset, 1500
# steps), seeds 1-3, trained three ways that differ only in the weights inference uses: the last
# step's (base), the mean over the last 50 % of the audio steps (avg50) and over the last 25 %
# (avg25). Each is scored by `neraf eval` on the 60 held-out RIRs and on 400 RIRs at new
# microphone positions (200 random microphones x 2 sources, `neraf synth` seed 4, as
# scripts/raf_gap.sh), with the other two as --ablation-runs, so every paired per-RIR difference
# (against nearest, linear and each other) is in the JSONs; scripts/raf_gap.py's summary (means
# over seeds, SE over seeds, per-RIR SEs) goes to DIR/audio_average.json.
# Usage: scripts/audio_average.sh [DIR]   (default build/audio_average; NERAF=build/neraf)
# Trains 1 + 9 runs (two at a time, one thread each) and makes 9 evaluations: about 20 min on a
# 2-core AMD EPYC Zen 5 (2026-12-07: vision run 4 min, audio runs 2 min each, evaluations 3 min). A run or evaluation already in DIR is kept.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-build/audio_average}
NERAF=${NERAF:-build/neraf}
D=$DIR/data
R=$DIR/runs
STUDY=audio_average
# shellcheck source=scripts/study_lib.sh
. scripts/study_lib.sh
study_check_tools numpy python3-numpy
mkdir -p "$R"
synth_once furnished_room raf_furnished --seed 1
synth_once furnished_room novel400 --mics random --mic-count 200 --seed 4 --gain-from "$D/raf_furnished"
train_once vision --data "$D/raf_furnished" --modality vision --seed 1
VARIANTS=(base avg50 avg25)
declare -A AVERAGE=([base]=0 [avg50]=0.5 [avg25]=0.25)
for s in 1 2 3; do
  pids=()
  for v in "${VARIANTS[@]}"; do
    train_once "${v}_s$s" --data "$D/raf_furnished" --modality audio --vision-run "$R/vision" \
      --steps 1500 --seed "$s" --threads 1 --audio-average "${AVERAGE[$v]}" &
    pids+=($!)
    [ ${#pids[@]} -lt 2 ] || { wait "${pids[0]}"; pids=("${pids[@]:1}"); }
  done
  for p in "${pids[@]}"; do wait "$p"; done
done
evals=()
for v in "${VARIANTS[@]}"; do
  for s in 1 2 3; do
    json=$DIR/eval_${v}_s$s.json
    others=()
    for o in "${VARIANTS[@]}"; do [ "$o" = "$v" ] || others+=("$R/${o}_s$s"); done
    [ -f "$json" ] || "$NERAF" eval --run "$R/${v}_s$s" --skip-vision --no-images --quiet \
      --novel-data "$D/novel400" --images "$DIR/csv_${v}_s$s" --json "$json" \
      --ablation-runs "$(IFS=,; echo "${others[*]}")" >/dev/null
    evals+=("$json")
  done
done
PYTHONPATH=scripts /usr/bin/python3 - "$DIR" "${evals[@]}" <<'EOF'
import json, os, sys, time
from experiments_report import machine
from raf_gap import summarise_evals
out, evals = sys.argv[1], sys.argv[2:]
result = {"command": "scripts/audio_average.sh " + out, "machine": f"{machine()}, {os.cpu_count()} cores",
          "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
for i, v in enumerate(["base", "avg50", "avg25"]):  # each variant as the main run of 3 seeds
    result[v] = summarise_evals(evals[3 * i:3 * i + 3])
path = os.path.join(out, "audio_average.json")
with open(path + ".tmp", "w") as f:
    json.dump(result, f, indent=1)
os.replace(path + ".tmp", path)
print("audio_average: wrote", path)
EOF
