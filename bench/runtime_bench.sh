#!/usr/bin/env bash
# The runtime's numbers for docs/RUNTIME.md and docs/BENCHMARKS.md, in one session on an idle
# machine: neraf_rt (network part, whole RIR with Griffin-Lim, model load, streaming) beside the
# LibTorch query path on the same preset sizes, and `neraf eval` throughput on a cpu-preset run of
# the demo room (SoundSpaces layout) through --run and --model.
#   bench/runtime_bench.sh            raw outputs in build/bench-runtime/, summary in
#                                     bench/results/runtime.json
#   RESULT=bench/results/x.json ...   the summary there instead
# Needs a built tree (scripts/build.sh). Takes about 10 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
B=build
OUT=$B/bench-runtime
mkdir -p "$OUT"
reps=(--benchmark_repetitions=5 --benchmark_report_aggregates_only=true)
RESULT=${RESULT:-bench/results/runtime.json}
load_before=$(cut -d' ' -f1-3 /proc/loadavg)

# neraf_rt with OpenBLAS on one thread (the advice of docs/RUNTIME.md); the workspace's own
# helper threads (threads = 0: one per channel) still use both cores.
OMP_NUM_THREADS=1 "$B/neraf_bench_runtime" "${reps[@]}" \
  --benchmark_out="$OUT/runtime.json" --benchmark_out_format=json
# The LibTorch path (NAcF with the scene feature cached, as AudioRun queries it), all cores.
"$B/neraf_bench_acoustic" --benchmark_filter='BM_RenderStftCachedFeature' \
  --benchmark_out="$OUT/libtorch.json" --benchmark_out_format=json

# neraf eval: a short cpu-preset joint run (the network has its full size after one step; the
# quality is not what is measured), scored through --run and through its export; "nearest" and
# "linear" are scored together (their seconds are the same).
N=$B/neraf
"$N" synth --preset demo --layout soundspaces --out "$OUT/scene" --seed 1 --force --quiet
# The same room heard at 29 new microphone positions (x 4 headings x 4 sources = 464 RIRs, as many
# as the scene has): neraf eval scores --novel-data, and refuses the run's own dataset there.
"$N" synth --preset demo --layout soundspaces --mics random --mic-count 29 --seed 2 \
  --gain-from "$OUT/scene" --out "$OUT/novel" --force --quiet
"$N" train --data "$OUT/scene" --out "$OUT/run" --steps 40 --audio-start-step 1 --force --quiet
"$N" export --run "$OUT/run" --out "$OUT/run.nrf" | tee "$OUT/export_fp32.txt"
"$N" export --run "$OUT/run" --out "$OUT/run_bf16.nrf" --precision bf16 | tee "$OUT/export_bf16.txt"
# All 464 RIRs of the new positions, 3 times each.
for source in run model; do
  if [ $source = run ]; then arg=(--run "$OUT/run"); else arg=(--model "$OUT/run.nrf"); fi
  for rep in 1 2 3; do
    "$N" eval "${arg[@]}" --json "$OUT/eval_${source}_$rep.json" --skip-vision --no-images --quiet \
      --novel-data "$OUT/novel"
  done
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

python3 - "$OUT" "$load_before" "$load_after" "$RESULT" <<'PY'
import json, os, platform, statistics, subprocess, sys, datetime
out, load_before, load_after, result = sys.argv[1:]
def medians(path):
    j = json.load(open(path))
    return {b["run_name"]: b["real_time"] if "real_time" in b else b["cpu_time"]
            for b in j["benchmarks"] if b.get("aggregate_name") == "median"}, j["context"]
def counters(path, name):
    for b in json.load(open(path))["benchmarks"]:
        if b["run_name"] == name and b.get("aggregate_name") == "median":
            return {k: b[k] for k in ("fp32_file_MB", "bf16_file_MB")}
rt, ctx = medians(f"{out}/runtime.json")
lt, _ = medians(f"{out}/libtorch.json")
runs = json.load(open(f"{out}/runtime.json"))["benchmarks"]
units = {b["run_name"]: b["time_unit"] for b in runs}
compute = {b["run_name"]: b["label"] for b in runs if b.get("label")}  # float32, bfloat16-...
evals = {}
for source in ("run", "model"):
    reps = [json.load(open(f"{out}/eval_{source}_{r}.json"))["audio"]["novel"] for r in (1, 2, 3)]
    evals[source] = {m: {"n_rirs": reps[0][m]["n_rirs"],
                         "seconds": [a[m]["seconds"] for a in reps],
                         "median_rirs_per_s": statistics.median(a[m]["n_rirs"] / a[m]["seconds"]
                                                                for a in reps)}
                     for m in ("neraf", "nearest")}
sizes = {p: os.path.getsize(f"{out}/{f}") for p, f in (("fp32", "run.nrf"), ("bf16", "run_bf16.nrf"))}
cpu = subprocess.run(["sh", "-c", "lscpu | grep 'Model name' | cut -d: -f2"],
                     capture_output=True, text=True).stdout.strip()
summary = {
    "command": "bench/runtime_bench.sh",
    "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    "machine": f"{cpu}, {os.cpu_count()} cores",
    "load_avg_before": load_before, "load_avg_after": load_after,
    "note": "idle machine; neraf_rt with OMP_NUM_THREADS=1; times are medians of 5 repetitions",
    "runtime_median": {k: {"time": v, "unit": units.get(k, ""), **({"compute": compute[k]} if k in compute else {})}
                       for k, v in rt.items()},
    "libtorch_median_ms": lt,
    "eval": evals,
    "model_file_bytes_cpu_preset_run": sizes,
    "model_file_MB_by_preset": {p: counters(f"{out}/runtime.json", f"BM_Load/paper:{i}/real_time")
                                for p, i in (("cpu", 0), ("paper", 1))},
    "export_check": {p: open(f"{out}/export_{p}.txt").read().strip() for p in ("fp32", "bf16")},
}
json.dump(summary, open(result, "w"), indent=2)
print(json.dumps(summary, indent=2))
PY
