#!/bin/bash
# Where the default neraf loses to the baselines in the RAF-layout furnished room (issue 13), on
# experiments 2 and 5's runs (made by `EXPERIMENTS="2 5" scripts/experiments.sh`; read, not changed):
#   1. a larger set of new microphone positions than the experiments' 80 RIRs: 200 random
#      microphones x 2 sources = 400 RIRs of the same room (neraf synth, seed 4), scored with each
#      seed's run, its grid ablations and loss variants (--ablation-runs: experiments 2's and 5's
#      other runs of the same seed) by `neraf eval --novel-data`, which scores the 60 held-out
#      RIRs again too;
#   2. scripts/raf_gap.py on the runs' own per-RIR CSVs and on those evaluations.
# Usage: scripts/raf_gap.sh [DIR]   (default build/raf_gap; OUT=build/experiments, NERAF=build/neraf)
# Writes DIR/eval_sN.json, DIR/csv_sN/ and DIR/raf_gap.json. About 5 min on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-build/raf_gap}
OUT=${OUT:-build/experiments}
NERAF=${NERAF:-build/neraf}
VARIANTS="e2_full e2_grid_none e2_grid_zeros e2_S24 e2_S64 e2_features_local e2_features_both
  e5_loss_sc_sll1 e5_loss_mse"
for s in 1 2 3; do
  for v in $VARIANTS; do
    run=$OUT/runs/${v%%_*}_raf_furnished_${v#*_}_s$s
    [ -f "$run/done" ] || {
      echo "raf_gap: $run is not a finished run; make it with" \
        "EXPERIMENTS=\"2 5\" E2_ROOMS=raf_furnished scripts/experiments.sh" >&2
      exit 1
    }
  done
done
/usr/bin/python3 -c 'import numpy' 2>/dev/null || {
  echo "raf_gap: /usr/bin/python3 has no numpy; install it with: apt-get install python3-numpy" >&2
  exit 1
}
mkdir -p "$DIR"
"$NERAF" synth --preset furnished_room --mics random --mic-count 200 --seed 4 \
  --gain-from "$OUT/data/raf_furnished" --out "$DIR/novel400" --force --quiet
evals=()
for s in 1 2 3; do
  ablations=()
  for v in $VARIANTS; do
    [ "$v" = e2_full ] || ablations+=("$OUT/runs/${v%%_*}_raf_furnished_${v#*_}_s$s")
  done
  # --images: the per-RIR CSVs go to DIR, so the run's own (experiment 2's) stay as they are
  "$NERAF" eval --run "$OUT/runs/e2_raf_furnished_full_s$s" --skip-vision --no-images --quiet \
    --novel-data "$DIR/novel400" --images "$DIR/csv_s$s" --json "$DIR/eval_s$s.json" \
    --ablation-runs "$(IFS=,; echo "${ablations[*]}")" >/dev/null
  evals+=("$DIR/eval_s$s.json")
done
/usr/bin/python3 scripts/raf_gap.py --out "$OUT" --neraf "$NERAF" --evals "${evals[@]}" \
  --json "$DIR/raf_gap.json"
