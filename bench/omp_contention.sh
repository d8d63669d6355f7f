#!/usr/bin/env bash
# Two neraf trainings at once on one machine: how much each loses when both ask for all cores,
# and whether OpenMP's wait policy matters. LibTorch and OpenBLAS share libgomp's thread pool,
# whose idle threads spin before they sleep (300,000 turns unless told); a spinning thread of one
# process holds a core the other process's working thread needs.
# Cases, each with idle threads spinning 300,000 turns (libgomp's default), 10,000, 1,000 (what
# neraf sets unless GOMP_SPINCOUNT or OMP_WAIT_POLICY is set) and not at all (PASSIVE)
# (POLICIES="libgomp spin10000 neraf PASSIVE"), training steps/s over the whole run:
#   one        one process, --threads = all cores (the default)
#   two_all    two processes at once, each --threads = all cores
#   two_split  two processes at once, each --threads = cores / 2
#   bench/omp_contention.sh [OUT_JSON]      default build/bench/omp_contention.json
#   STEPS=40 REPS=3 bench/omp_contention.sh
# Run it alone on the machine; the load before and after is recorded.
set -euo pipefail
cd "$(dirname "$0")/.."
NERAF=build/neraf
WORK=${WORK:-build/bench/omp_contention}
OUT=${1:-build/bench/omp_contention.json}
STEPS=${STEPS:-40}
REPS=${REPS:-3}
POLICIES=${POLICIES:-libgomp spin10000 neraf PASSIVE}
[ -x "$NERAF" ] || { echo "bench/omp_contention.sh: build neraf first (scripts/build.sh)" >&2; exit 1; }
CORES=$(nproc)
HALF=$(((CORES + 1) / 2))
mkdir -p "$WORK"
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
[ -f "$WORK/scene/transforms.json" ] ||
  $NERAF synth --preset demo --layout soundspaces --out "$WORK/scene" --seed 3 --force --quiet

# The cpu preset, joint with audio from the first step.
common=(--data "$WORK/scene" --steps "$STEPS" --audio-start-step -1 --quiet --force)
steps_per_s() { sed -n 's/.*trained steps [0-9.]* in [0-9.]* s (\([0-9.]*\) steps\/s).*/\1/p' "$1"; }
# run POLICY THREADS NAME...: one training per NAME, all at once, with libgomp's idle threads
# waiting as POLICY says (libgomp: GOMP_SPINCOUNT=300000, libgomp's own default; spin10000:
# GOMP_SPINCOUNT=10000; neraf: nothing set, so neraf runs itself with GOMP_SPINCOUNT=1000;
# PASSIVE: OMP_WAIT_POLICY=PASSIVE, no spinning); prints their steps/s
run() {
  local policy=$1 threads=$2 pids=() pid name wait_env
  shift 2
  case $policy in
    libgomp) wait_env=(GOMP_SPINCOUNT=300000) ;;
    spin10000) wait_env=(GOMP_SPINCOUNT=10000) ;;
    neraf) wait_env=() ;;
    PASSIVE) wait_env=(OMP_WAIT_POLICY=PASSIVE) ;;
  esac
  for name in "$@"; do
    env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT "${wait_env[@]}" $NERAF train "${common[@]}" \
      --threads "$threads" --out "$WORK/$name" >"$WORK/$name.out" &
    pids+=($!)
  done
  for pid in "${pids[@]}"; do wait "$pid"; done  # a failed training stops the script (set -e)
  for name in "$@"; do steps_per_s "$WORK/$name.out"; done
}

rows=()
for ((r = 0; r < REPS; ++r)); do
  for policy in $POLICIES; do
    rows+=("$policy one $CORES $(run $policy "$CORES" a | tr '\n' ' ')")
    rows+=("$policy two_all $CORES $(run $policy "$CORES" a b | tr '\n' ' ')")
    rows+=("$policy two_split $HALF $(run $policy "$HALF" a b | tr '\n' ' ')")
    printf '%s\n' "${rows[@]: -3}" >&2
  done
done

mkdir -p "$(dirname "$OUT")"
printf '%s\n' "${rows[@]}" >"$WORK/rows.txt"
python3 - "$OUT.tmp" "$STEPS" "$load_before" "$(cut -d' ' -f1-3 /proc/loadavg)" \
  "$WORK/rows.txt" <<'EOF'
import datetime, json, statistics, subprocess, sys
out, steps, load_before, load_after, rows = sys.argv[1:]
runs, medians = [], {}
for line in open(rows).read().split("\n"):
    if not line.strip():
        continue
    policy, case, threads, *rates = line.split()
    runs.append({"omp_wait_policy": policy, "case": case, "threads_per_process": int(threads),
                 "steps_per_s": [float(x) for x in rates]})
for policy in dict.fromkeys(r["omp_wait_policy"] for r in runs):
    for case in ("one", "two_all", "two_split"):
        xs = [x for r in runs if r["omp_wait_policy"] == policy and r["case"] == case
              for x in r["steps_per_s"]]
        medians.setdefault(policy, {})[case] = statistics.median(xs)
cpu = open("/proc/cpuinfo").read().split("model name")[1].split("\n")[0].split(":")[1].strip()
doc = {
    "command": f"bench/omp_contention.sh (STEPS={steps}, REPS={len(runs) // (3 * len(medians))})",
    "what": "neraf train (cpu preset, joint, audio from step 0) on the demo room: one process "
            "with all cores' threads, two at once with all cores' threads each (two_all) and "
            "with half each (two_split); idle OpenMP threads spinning 300,000 turns before they "
            "sleep (libgomp: GOMP_SPINCOUNT=300000, libgomp's default), 10,000 (spin10000), "
            "1,000 (neraf: nothing set, neraf sets GOMP_SPINCOUNT=1000) or none (PASSIVE: "
            "OMP_WAIT_POLICY=PASSIVE); steps/s "
            "of each process over its whole run; medians over processes and repetitions",
    "machine": f"{cpu}, {subprocess.check_output(['nproc']).decode().strip()} cores",
    "date": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"),
    "load_before": load_before, "load_after": load_after,
    "runs": runs, "median_steps_per_s": medians,
}
json.dump(doc, open(out, "w"), indent=2)
EOF
mv "$OUT.tmp" "$OUT"
python3 -c "import json; print(json.dumps(json.load(open('$OUT'))['median_steps_per_s']))"
echo "bench/omp_contention.sh: wrote $OUT"
