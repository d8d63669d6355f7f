#!/usr/bin/env bash
# What the runtime's bfloat16 path costs in the metrics, on a trained field: the run exported in
# float32 and in bfloat16, both scored by `neraf eval --model` on the same RIRs (its held-out split
# and a second dataset at new microphone positions), then paired per-RIR differences bf16 − fp32
# (mean ± standard error, and the largest) of T60, C50, EDT and the STFT error.
#   RUN=demo-out/run NOVEL=demo-out/novel OUT=build/bf16-accuracy bench/runtime_bf16_accuracy.sh
# RUN and NOVEL as `scripts/demo.sh` leaves them; OUT gets the model files, eval JSONs, per-RIR
# CSVs and summary.json (copy it under bench/results/ to keep it). Accuracy only: the timings of
# these evals are not what is measured. About a minute on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
NERAF=${NERAF:-build/neraf}
RUN=${RUN:?set RUN to a trained run folder (scripts/demo.sh leaves demo-out/run)}
NOVEL=${NOVEL:?set NOVEL to a dataset of new microphone positions (demo-out/novel)}
OUT=${OUT:-build/bf16-accuracy}
mkdir -p "$OUT"
for p in fp32 bf16; do
  # Its line names the file's size and its largest difference from the LibTorch path.
  "$NERAF" export --run "$RUN" --out "$OUT/model_$p.nrf" --precision "$p" | tee "$OUT/export_$p.txt"
  "$NERAF" eval --model "$OUT/model_$p.nrf" --json "$OUT/eval_$p.json" --images "$OUT/img_$p" \
    --novel-data "$NOVEL" --skip-vision --no-baselines --quiet
  cp "$OUT/img_$p/audio_per_rir.csv" "$OUT/${p}_audio_per_rir.csv"
  cp "$OUT/img_$p/audio_novel_per_rir.csv" "$OUT/${p}_audio_novel_per_rir.csv"
done

python3 - "$OUT" "$RUN" "$NOVEL" "$("$NERAF" --version | head -n 1)" <<'PY'
import csv, json, math, os, platform, subprocess, sys, datetime
out, run, novel, version = sys.argv[1:]
METRICS = ["t60_error_pct", "c50_error_db", "edt_error_s", "stft_error"]
def rows(path):
    with open(path) as f:
        return {r["rir_id"]: r for r in csv.DictReader(f) if r["method"] == "neraf"}
def paired(a, b):
    res = {}
    for m in METRICS:
        d = [float(a[k][m]) - float(b[k][m]) for k in a if k in b]
        d = [x for x in d if math.isfinite(x)]
        n = len(d)
        mean = sum(d) / n
        se = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1) / n)
        res[m] = {"mean_difference": mean, "standard_error": se, "n": n,
                  "max_abs_difference": max(abs(x) for x in d)}
    return res
cpu, flags = "?", ""
for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
    if line.startswith("Model name"): cpu = line.split(":", 1)[1].strip()
    if line.startswith("Flags"): flags = line.split()
# The kernel neraf_rt picks for a bf16 file (runtime/bf16_gemm.h: best_bf16_kernel).
kernel = ("bfloat16-amx" if "amx_bf16" in flags else
          "bfloat16-avx512" if "avx512_bf16" in flags else "float32 (no bf16 kernel)")
summary = {
    "command": f"RUN={run} NOVEL={novel} bench/runtime_bf16_accuracy.sh",
    "neraf": version, "date": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%MZ"),
    "machine": {"cpu": cpu, "cores": os.cpu_count(), "host": platform.node()},
    "compute": {"fp32": "float32", "bf16": kernel},
    "export": {p: open(f"{out}/export_{p}.txt").read().strip() for p in ("fp32", "bf16")},
    "paired_bf16_minus_fp32": {
        split: paired(rows(f"{out}/bf16_{name}"), rows(f"{out}/fp32_{name}"))
        for split, name in (("held_out", "audio_per_rir.csv"), ("novel", "audio_novel_per_rir.csv"))}}
with open(f"{out}/summary.json.tmp", "w") as f:
    json.dump(summary, f, indent=1)
os.replace(f"{out}/summary.json.tmp", f"{out}/summary.json")
for split, r in summary["paired_bf16_minus_fp32"].items():
    print(split + ": " + ", ".join(f"{m} {v['mean_difference']:+.5f} ± {v['standard_error']:.5f} "
                                  f"(max {v['max_abs_difference']:.4f}, n {v['n']})"
                                  for m, v in r.items()))
PY
