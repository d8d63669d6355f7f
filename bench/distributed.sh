#!/usr/bin/env bash
# Data-parallel training (train/distributed.h, issue 14 §3): 1 → 2 processes with 1 thread each,
# the same global batch, on this machine: steps/s, speed-up and scaling efficiency (speed-up / 2)
# for the cpu preset's joint and vision-only training (--dist-overlap on; joint also off), and the gradient all-reduce per step (bytes;
# the wall time it adds to a step: flattening and starting buckets, inside the backward pass too,
# then waiting for them, which includes waiting for the slower rank; the buckets started during
# the backward pass) for the cpu and paper presets.
#   bench/distributed.sh [OUT_JSON]      default build/bench/distributed.json
#   STEPS=30 REPS=3 PAPER_STEPS=3 bench/distributed.sh
# Run it alone on the machine (flock /tmp/neraf-build.lock on the shared one); the load before
# and after is recorded.
set -euo pipefail
cd "$(dirname "$0")/.."
NERAF=build/neraf
WORK=${WORK:-build/bench/distributed}
OUT=${1:-build/bench/distributed.json}
STEPS=${STEPS:-30}
REPS=${REPS:-3}
PAPER_STEPS=${PAPER_STEPS:-3}
[ -x "$NERAF" ] || { echo "bench/distributed.sh: build neraf first (scripts/build.sh)" >&2; exit 1; }
mkdir -p "$WORK"
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
[ -f "$WORK/scene/transforms.json" ] ||
  $NERAF synth --preset demo --layout soundspaces --out "$WORK/scene" --seed 3 --force --quiet

# "trained steps 0..N in X s (Y steps/s)...; all-reduce B MB/step, T ms/step; ..." → JSON fields
parse() {
  python3 - "$1" <<'EOF'
import re, sys
line = open(sys.argv[1]).read()
m = re.search(r"trained steps \d+\.\.(\d+) in ([\d.]+) s \(([\d.]+) steps/s\)", line)
out = {"steps": int(m.group(1)), "seconds": float(m.group(2)), "steps_per_s": float(m.group(3))}
a = re.search(r"all-reduce ([\d.]+) MB/step, ([\d.]+) ms/step", line)
if a:
    out["allreduce_mb_per_step"] = float(a.group(1))
    out["allreduce_ms_per_step"] = float(a.group(2))
b = re.search(r"\((\d+)/(\d+) buckets started during backward\)", line)
if b:
    out["buckets_started_during_backward"] = int(b.group(1))
    out["buckets"] = int(b.group(2))
print(out.__repr__().replace("'", '"'))
EOF
}

# The cpu preset, joint with audio from the first step, and vision only: 1 process, then 2
# (1 thread each), alternating.
common=(--data "$WORK/scene" --steps "$STEPS" --threads 1 --quiet --force)
joint=(--audio-start-step -1)
vision=(--modality vision)
one=() two=() twooff=() vone=() vtwo=()
for ((r = 0; r < REPS; ++r)); do
  $NERAF train "${common[@]}" "${joint[@]}" --out "$WORK/one" >"$WORK/one.out"
  one+=("$(parse "$WORK/one.out")")
  $NERAF launch -n 2 -- train "${common[@]}" "${joint[@]}" --dist-overlap on --out "$WORK/two" \
    >"$WORK/two.out"
  two+=("$(parse "$WORK/two.out")")
  $NERAF launch -n 2 -- train "${common[@]}" "${joint[@]}" --dist-overlap off --out "$WORK/twooff" \
    >"$WORK/twooff.out"
  twooff+=("$(parse "$WORK/twooff.out")")
  $NERAF train "${common[@]}" "${vision[@]}" --out "$WORK/vone" >"$WORK/vone.out"
  vone+=("$(parse "$WORK/vone.out")")
  $NERAF launch -n 2 -- train "${common[@]}" "${vision[@]}" --dist-overlap on --out "$WORK/vtwo" \
    >"$WORK/vtwo.out"
  vtwo+=("$(parse "$WORK/vtwo.out")")
done
batch=$(python3 -c "import json; c = json.load(open('$WORK/one/config.json')); print(c['rays_per_batch'], c['audio']['batch_size'])")
# The paper preset: the all-reduce only (its steps take long on 2 cores; the bytes do not depend
# on the ray batch, so a small one is used).
$NERAF launch -n 2 -- train --data "$WORK/scene" --preset paper --steps "$PAPER_STEPS" \
  --audio-start-step -1 --rays 512 --threads 1 --dist-overlap on --quiet --force --out "$WORK/paper" \
  >"$WORK/paper.out"
paper=$(parse "$WORK/paper.out")

mkdir -p "$(dirname "$OUT")"
python3 - "$OUT.tmp" "$STEPS" "$PAPER_STEPS" "$load_before" "$(cut -d' ' -f1-3 /proc/loadavg)" \
  "$(IFS='|'; echo "${one[*]}")" "$(IFS='|'; echo "${two[*]}")" "$paper" \
  "$(IFS='|'; echo "${vone[*]}")" "$(IFS='|'; echo "${vtwo[*]}")" "$(IFS='|'; echo "${twooff[*]}")" \
  $batch <<'EOF'
import json, statistics, subprocess, sys, datetime
out, steps, paper_steps, load_before, load_after, one, two, paper, vone, vtwo, twooff, rays, slices = sys.argv[1:]
twooff = [json.loads(x) for x in twooff.split("|")]
one = [json.loads(x) for x in one.split("|")]
two = [json.loads(x) for x in two.split("|")]
vone = [json.loads(x) for x in vone.split("|")]
vtwo = [json.loads(x) for x in vtwo.split("|")]
v1 = statistics.median(r["steps_per_s"] for r in vone)
v2 = statistics.median(r["steps_per_s"] for r in vtwo)
cpu = open("/proc/cpuinfo").read().split("model name")[1].split("\n")[0].split(":")[1].strip()
mem = int(open("/proc/meminfo").read().split("MemTotal:")[1].split()[0]) / 1048576
m1 = statistics.median(r["steps_per_s"] for r in one)
m2 = statistics.median(r["steps_per_s"] for r in two)
doc = {
  "command": f"bench/distributed.sh (STEPS={steps}, REPS={len(one)}, PAPER_STEPS={paper_steps})",
  "what": f"neraf train (cpu preset, joint with audio from step 0, global batch {rays} rays + "
          f"{slices} audio slices; and vision only; --threads 1) as 1 process and as neraf "
          "launch -n 2 (1 thread each, half the batch each; --dist-overlap on, joint also off); steps/s over the whole run; the "
          "gradient all-reduce per step of rank 0; the paper preset's all-reduce with --rays 512",
  "machine": f"{cpu}, {subprocess.check_output(['nproc']).decode().strip()} cores, {mem:.0f} GiB",
  "date": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"),
  "load_before": load_before, "load_after": load_after,
  "cpu_one_process": one, "cpu_two_processes": two,
  "cpu_median_steps_per_s": {"one": m1, "two": m2},
  "cpu_speedup": m2 / m1, "cpu_scaling_efficiency": m2 / m1 / 2,
  "cpu_allreduce": {"mb_per_step": statistics.median(r["allreduce_mb_per_step"] for r in two),
                    "ms_per_step": statistics.median(r["allreduce_ms_per_step"] for r in two)},
  "cpu_two_processes_overlap_off": twooff,
  "cpu_overlap_off": {
    "median_steps_per_s": statistics.median(r["steps_per_s"] for r in twooff),
    "allreduce_ms_per_step": statistics.median(r["allreduce_ms_per_step"] for r in twooff),
    "overlap_on_over_off_steps_per_s": m2 / statistics.median(r["steps_per_s"] for r in twooff)},
  "cpu_vision_one_process": vone, "cpu_vision_two_processes": vtwo,
  "cpu_vision_median_steps_per_s": {"one": v1, "two": v2},
  "cpu_vision_speedup": v2 / v1, "cpu_vision_scaling_efficiency": v2 / v1 / 2,
  "cpu_vision_allreduce": {
    "mb_per_step": statistics.median(r["allreduce_mb_per_step"] for r in vtwo),
    "ms_per_step": statistics.median(r["allreduce_ms_per_step"] for r in vtwo)},
  "paper_two_processes": json.loads(paper),
}
json.dump(doc, open(out, "w"), indent=2)
EOF
mv "$OUT.tmp" "$OUT"
echo "wrote $OUT"
cat "$OUT"
