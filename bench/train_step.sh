#!/usr/bin/env bash
# The real joint training step at the cpu and paper presets (issue 14 §4): neraf_bench_train on the
# demo room, each case in its own process, then a summary with the grid update's and the acoustic
# field's share of the step (bench/bench_train_step.cpp says what each case runs).
#   bench/train_step.sh [OUT_JSON]      default build/bench/train_step.json
#   REPS=3 bench/train_step.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BENCH=build/neraf_bench_train
WORK=${WORK:-build/bench/train_step}
OUT=${1:-build/bench/train_step.json}
REPS=${REPS:-3}
[ -x "$BENCH" ] && [ -x build/neraf ] ||
  { echo "bench/train_step.sh: build neraf and neraf_bench_train first (scripts/build.sh)" >&2; exit 1; }
mkdir -p "$WORK"
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
[ -f "$WORK/demo/synth_info.json" ] ||
  build/neraf synth --preset demo --out "$WORK/demo" --seed 1 --force --quiet
for preset in cpu paper; do
  for mode in vision zeros joint; do
    NERAF_BENCH_DATA="$WORK/demo" "$BENCH" --benchmark_filter="BM_TrainStep/${preset}_${mode}/" \
      --benchmark_repetitions="$REPS" --benchmark_report_aggregates_only=true \
      --benchmark_out="$WORK/${preset}_${mode}.json" --benchmark_out_format=json >/dev/null
  done
done

python3 - "$WORK" "$OUT" "$load_before" "$REPS" <<'EOF'
import datetime, json, os, re, sys
work, out, load_before, reps = sys.argv[1:5]
cases = {}
for preset in ("cpu", "paper"):
    for mode in ("vision", "zeros", "joint"):
        j = json.load(open(os.path.join(work, f"{preset}_{mode}.json")))
        med = next(b for b in j["benchmarks"] if b.get("aggregate_name") == "median")
        cases[f"{preset}_{mode}"] = {"median_s": med["real_time"] / 1e3,
                                     "repetitions": med["iterations"],
                                     "rays": med["rays"], "audio_slices": med["audio_slices"],
                                     "grid_cells_per_step": med["grid_cells_per_step"]}
ctx = j["context"]
model = re.search(r"model name\s*:\s*(.*)", open("/proc/cpuinfo").read()).group(1)
result = {
    "command": f"bench/train_step.sh (REPS={reps})",
    "what": "one training step of the trainer on the demo room, audio from step 0: vision = the "
            "radiance field alone, zeros = joint with an all-zero grid (no grid update), joint = "
            "joint with the sampled grid (grid update with autograd into the radiance field); "
            "wall-clock medians of the repetitions, 2 threads",
    "machine": f"{model}, {os.cpu_count()} cores",
    "date": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"),
    "load_before": load_before,
    "load_after": " ".join(open("/proc/loadavg").read().split()[:3]),
    "cases": cases,
}
for preset in ("cpu", "paper"):
    v, z, g = (cases[f"{preset}_{m}"]["median_s"] for m in ("vision", "zeros", "joint"))
    result[preset] = {"joint_audio_step_s": g, "acoustic_field_s": z - v, "grid_update_s": g - z,
                      "vision_s": v}
open(out + ".tmp", "w").write(json.dumps(result, indent=2) + "\n")
os.replace(out + ".tmp", out)
print("wrote", out)
for preset in ("cpu", "paper"):
    r = result[preset]
    print(f"{preset:5s} joint audio step {r['joint_audio_step_s']:.3f} s = vision {r['vision_s']:.3f}"
          f" + acoustic field {r['acoustic_field_s']:.3f} + grid update {r['grid_update_s']:.3f}")
EOF
