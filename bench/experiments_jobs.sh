#!/usr/bin/env bash
# What JOBS=2 buys scripts/experiments.sh on this machine: one of experiment 2's runs (the full
# model, audio-only on a frozen vision run, 1500 steps) for two seeds, trained one after the other
# with all cores (as JOBS=1 trains) and then both at once with half the cores each (as JOBS=2
# does). throughput_ratio: the runs per hour of the second against the first.
#   scripts/experiments.sh (any call that made ROOM's dataset and vision run), then
#   bench/experiments_jobs.sh [OUT_JSON]          default build/bench/experiments_jobs.json
#   ROOM=occluded FLAGS="--grid-resolution 64" bench/experiments_jobs.sh
# Run it alone on the machine (the load before and after is recorded).
set -euo pipefail
cd "$(dirname "$0")/.."
EXP=build/experiments
NERAF=$EXP/neraf # the binary the experiments ran
ROOM=${ROOM:-raf_empty}
FLAGS=${FLAGS:-}
OUT=${1:-build/bench/experiments_jobs.json}
WORK=build/bench/experiments_jobs
for need in "$NERAF" "$EXP/runs/v_$ROOM/done"; do
  [ -e "$need" ] || {
    echo "bench/experiments_jobs.sh: $need is missing; run EXPERIMENTS=2 E2_ROOMS=$ROOM scripts/experiments.sh first" >&2
    exit 1
  }
done
mkdir -p "$WORK" "$(dirname "$OUT")"
CORES=$(nproc)
read -r -a flags <<<"$FLAGS"
# train SEED THREADS NAME: one run, its wall time in seconds on stdout
train() {
  local t0
  t0=$(date +%s.%N)
  "$NERAF" train --data "$EXP/data/$ROOM" --modality audio --vision-run "$EXP/runs/v_$ROOM" \
    --seed "$1" --steps 1500 "${flags[@]}" --threads "$2" --out "$WORK/$3" --force --quiet \
    >"$WORK/$3.log" 2>&1
  awk "BEGIN { printf \"%.1f\", $(date +%s.%N) - $t0 }"
}
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
started=$(date -u +%FT%TZ)
alone1=$(train 1 "$CORES" alone_s1)
alone2=$(train 2 "$CORES" alone_s2)
t0=$(date +%s.%N)
train 1 $((CORES / 2)) pair_s1 >"$WORK/pair_s1.s" &
train 2 $((CORES / 2)) pair_s2 >"$WORK/pair_s2.s" &
wait
pair_wall=$(awk "BEGIN { printf \"%.1f\", $(date +%s.%N) - $t0 }")
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
/usr/bin/python3 - "$OUT" "$ROOM" "$FLAGS" "$CORES" "$started" "$load_before" "$load_after" \
  "$alone1" "$alone2" "$(cat "$WORK/pair_s1.s")" "$(cat "$WORK/pair_s2.s")" "$pair_wall" <<'EOF'
import json, os, sys
out, room, flags, cores, started, load_before, load_after = sys.argv[1:8]
alone1, alone2, pair1, pair2, pair_wall = map(float, sys.argv[8:])
first_cpu = open("/proc/cpuinfo").read().split("\n\n")[0]
info = {k.strip(): v.strip() for k, v in (l.split(":", 1) for l in first_cpu.splitlines() if ":" in l)}
avx512 = "with" if "avx512f" in info.get("flags", "").split() else "without"
machine = (f"{info.get('model name', '?')} (family {info.get('cpu family', '?')}, model "
           f"{info.get('model', '?')}, {avx512} AVX-512)")
result = {
    "command": "bench/experiments_jobs.sh", "machine": machine, "cores": int(cores),
    "started_utc": started, "load_before": load_before, "load_after": load_after,
    "run": f"experiment 2's {room} run, audio-only, 1500 steps, seeds 1 and 2, flags '{flags}'",
    "one_at_a_time_all_cores_s": [alone1, alone2],
    "two_at_once_half_cores_s": [pair1, pair2],
    "two_at_once_wall_s": pair_wall,
    "throughput_ratio": round((alone1 + alone2) / pair_wall, 3),
}
tmp = out + ".tmp"
with open(tmp, "w") as f:
    json.dump(result, f, indent=2)
os.replace(tmp, out)
print(json.dumps(result, indent=2))
EOF
