#!/usr/bin/env bash
# Single-scene vs multi-scene acoustic fields on three simulated rooms of different size and
# absorption (issue 14 §2, the paper's "generalization on multiple scenes"), and the grid
# ablations in the multi-scene setting:
#   1. `neraf synth` small_dead (3 × 2.4 × 2.6 m, absorbing), demo (4 × 2.7 × 3.5 m),
#      large_live (12 × 4.5 × 9 m hall, hard surfaces);
#   2. a short vision run per room (its radiance field fills that room's grid);
#   3. per seed: one audio run per room on its own (AUDIO_STEPS steps), and one audio run over all
#      three rooms with --grid sampled, zeros and none, of 3 × AUDIO_STEPS steps: the same total
#      number of training slices as the three single runs together (the compute budget of
#      training them separately), which the batches spread over the rooms in proportion to their
#      training slices (RIRs × each room's own frames);
#      and, as a control for the multi-scene run's 3× optimizer steps, one run per room on its own
#      with 3 × AUDIO_STEPS steps too ("single_long");
#   4. `neraf eval` of every run on each room's held-out split; per-RIR paired differences
#      (multi − single, sampled − zeros / none) with standard errors from the per-RIR CSVs.
# Quality only (not timing): run it with THREADS=1 and without the build lock.
# Usage: bench/multiscene.sh   (env: NERAF, WORK, RESULT, SEEDS, VISION_STEPS, AUDIO_STEPS, THREADS;
# START, LOAD_BEFORE, LOAD_AFTER: the runs' start and load when a later call only gathers them, e.g. after
# running one seed per core with SEEDS=1, SEEDS=2, ... into one WORK)
set -euo pipefail
cd "$(dirname "$0")/.."
NERAF=${NERAF:-build/neraf}
WORK=${WORK:-/tmp/neraf-multiscene}
RESULT=${RESULT:-bench/results/multiscene.json}
SEEDS=${SEEDS:-1}
VISION_STEPS=${VISION_STEPS:-400}
AUDIO_STEPS=${AUDIO_STEPS:-1000}
THREADS=${THREADS:-1}
ROOMS=(small_dead demo large_live)
mkdir -p "$WORK"
LOAD_BEFORE=${LOAD_BEFORE:-$(uptime)}
START=${START:-$(date -u +%FT%TZ)}
log() { echo "[$(date -u +%T)] $*"; }

for r in "${ROOMS[@]}"; do
  [ -d "$WORK/$r" ] || { log "synth $r"; "$NERAF" synth --preset "$r" --out "$WORK/$r" --seed 7 \
    --threads "$THREADS" --quiet; }
  [ -f "$WORK/v-$r/config.json" ] || { log "vision $r"; "$NERAF" train --data "$WORK/$r" \
    --modality vision --steps "$VISION_STEPS" --threads "$THREADS" --out "$WORK/v-$r" --quiet; }
done

multi_data=()
for r in "${ROOMS[@]}"; do multi_data+=(--data "$WORK/$r" --vision-run "$WORK/v-$r"); done
for seed in $SEEDS; do
  for r in "${ROOMS[@]}"; do
    for kind in short long; do
      run=$WORK/s$seed-$r steps=$AUDIO_STEPS
      [ $kind = long ] && run=$WORK/s$seed-$r-long steps=$((3 * AUDIO_STEPS))
      [ -f "$run/eval.json" ] && continue
      if [ ! -f "$run/trained" ]; then
        log "single $r seed $seed, $steps steps"
        "$NERAF" train --modality audio --data "$WORK/$r" --vision-run "$WORK/v-$r" \
          --steps "$steps" --seed "$seed" --threads "$THREADS" --out "$run" --force --quiet
        touch "$run/trained"
      fi
      # neraf writes the JSON atomically: it exists only once the evaluation is complete.
      "$NERAF" eval --run "$run" --json "$run/eval.json" --skip-vision --no-images \
        --threads "$THREADS" --quiet >"$run.eval.txt"
    done
  done
  for grid in sampled zeros none; do
    run=$WORK/m$seed-$grid
    [ -f "$run/config.json" ] && [ -n "$(ls "$run"/checkpoints/*.calibration.pt 2>/dev/null)" ] &&
      continue
    log "multi --grid $grid seed $seed"
    "$NERAF" train --modality audio "${multi_data[@]}" --steps $((3 * AUDIO_STEPS)) \
      --grid "$grid" --seed "$seed" --threads "$THREADS" --out "$run" --force --quiet
  done
  run=$WORK/m$seed-sampled
  if [ ! -f "$run/eval.json" ]; then
    log "eval multi seed $seed"
    "$NERAF" eval --run "$run" --json "$run/eval.json" --skip-vision --no-images \
      --threads "$THREADS" --ablation-runs "$WORK/m$seed-zeros,$WORK/m$seed-none" --quiet \
      >"$run.eval.txt"
  fi
done

LOAD_AFTER=${LOAD_AFTER:-$(uptime)}
mkdir -p "$(dirname "$RESULT")"
python3 - "$WORK" "$RESULT" "$SEEDS" "$AUDIO_STEPS" "$VISION_STEPS" "$THREADS" "$START" \
  "$LOAD_BEFORE" "$LOAD_AFTER" "${ROOMS[@]}" <<'EOF'
import csv, json, math, os, platform, subprocess, sys
work, result, seeds, audio_steps, vision_steps, threads, start, load0, load1 = sys.argv[1:10]
rooms = sys.argv[10:]
seeds = seeds.split()
METRICS = ["t60_error_pct", "c50_error_db", "edt_error_s", "stft_error"]

def per_rir(path, method):
    out = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            if row["method"] == method:
                out[row["rir_id"]] = {m: float(row[m]) for m in METRICS}
    return out

def paired(a, b):  # mean and standard error of a − b over the RIRs both scored (finite)
    res = {}
    for m in METRICS:
        d = [a[k][m] - b[k][m] for k in a if k in b and math.isfinite(a[k][m]) and math.isfinite(b[k][m])]
        n = len(d)
        mean = sum(d) / n if n else float("nan")
        var = sum((x - mean) ** 2 for x in d) / (n - 1) if n > 1 else float("nan")
        res[m] = {"mean_difference": mean, "standard_error": math.sqrt(var / n) if n > 1 else None,
                  "n": n}
    return res

cpu = "?"
try:
    for line in subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines():
        if line.startswith("Model name"): cpu = line.split(":", 1)[1].strip()
except Exception:
    pass
out = {"command": "bench/multiscene.sh", "date": start, "machine": {"cpu": cpu, "cores": os.cpu_count(),
       "host": platform.node()}, "load_before": load0, "load_after": load1,
       "settings": {"seeds": seeds, "audio_steps_single": int(audio_steps),
                    "audio_steps_multi": 3 * int(audio_steps), "vision_steps": int(vision_steps),
                    "threads": int(threads), "preset": "cpu", "rooms": rooms}, "seeds": {}}
tables = {}  # room → seed → method → per-RIR errors
for seed in seeds:
    ms = json.load(open(f"{work}/m{seed}-sampled/eval.json"))["audio"]
    entry = {"rooms": {}, "multi_mean": ms["mean"]}
    single_means = {m: 0.0 for m in METRICS}
    long_means = {m: 0.0 for m in METRICS}
    for r in rooms:
        single = json.load(open(f"{work}/s{seed}-{r}/eval.json"))["audio"]
        mcsv = f"{work}/m{seed}-sampled/eval/{r}/audio_per_rir.csv"
        scsv = f"{work}/s{seed}-{r}/eval/audio_per_rir.csv"
        multi = per_rir(mcsv, "neraf")
        long = json.load(open(f"{work}/s{seed}-{r}-long/eval.json"))["audio"]
        lcsv = f"{work}/s{seed}-{r}-long/eval/audio_per_rir.csv"
        tables.setdefault(r, {})[seed] = {
            "single": per_rir(scsv, "neraf"), "single_long": per_rir(lcsv, "neraf"),
            "zeros": per_rir(mcsv, "m%s-zeros" % seed), "none": per_rir(mcsv, "m%s-none" % seed),
            "linear": per_rir(mcsv, "linear"), "multi": multi}
        room = {"single": {k: single[k] for k in ("neraf", "linear", "nearest") if k in single},
                "single_long": {k: long[k] for k in ("neraf", "linear") if k in long},
                "paired_multi_minus_single_long": paired(multi, per_rir(lcsv, "neraf")),
                "multi": {k: ms["scenes"][r][k] for k in ("neraf", "linear", "nearest")},
                "multi_grid_zeros": ms["scenes"][r]["ablations"]["m%s-zeros" % seed],
                "multi_grid_none": ms["scenes"][r]["ablations"]["m%s-none" % seed],
                "paired_multi_minus_single": paired(multi, per_rir(scsv, "neraf")),
                "paired_multi_minus_zeros": paired(multi, per_rir(mcsv, "m%s-zeros" % seed)),
                "paired_multi_minus_none": paired(multi, per_rir(mcsv, "m%s-none" % seed)),
                "paired_multi_minus_linear": paired(multi, per_rir(mcsv, "linear"))}
        for m in METRICS:
            single_means[m] += single["neraf"][m] / len(rooms)
            long_means[m] += long["neraf"][m] / len(rooms)
        entry["rooms"][r] = room
    entry["single_mean"] = single_means
    entry["single_long_mean"] = long_means
    out["seeds"][seed] = entry

# Over the seeds: each comparison's per-RIR difference averaged over the seeds, then its mean and
# standard error over the RIRs (the paired difference of the seed-averaged models), and the
# standard error of the per-seed mean differences across the seeds (training randomness).
def seed_averaged(room_tables, method):
    keys = sorted(set.intersection(*(set(t[method]) for t in room_tables.values())))
    return {k: {m: sum(t[method][k][m] for t in room_tables.values()) / len(room_tables)
                for m in METRICS} for k in keys}

def across_seeds(values):
    n = len(values)
    mean = sum(values) / n
    se = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1) / n) if n > 1 else None
    return {"mean": mean, "standard_error_across_seeds": se, "per_seed": values}

COMPARED = ("single", "single_long", "zeros", "none", "linear")
if len(seeds) >= 2:
    across = {"rooms": {}, "all_rooms": {}}
    pooled = {method: {} for method in ("multi",) + COMPARED}
    for r in rooms:
        avg = {method: seed_averaged(tables[r], method) for method in ("multi",) + COMPARED}
        for method, rows in avg.items():
            pooled[method].update({f"{r}/{k}": v for k, v in rows.items()})
        entry = {"errors_mean_over_seeds": {method: {m: sum(x[m] for x in rows.values()) / len(rows)
                                                     for m in METRICS} for method, rows in avg.items()}}
        for other in COMPARED:
            entry[f"multi_minus_{other}"] = {
                "paired_per_rir": paired(avg["multi"], avg[other]),
                "per_seed": {m: across_seeds([paired(tables[r][s]["multi"], tables[r][s][other])[m]
                                              ["mean_difference"] for s in seeds]) for m in METRICS}}
        across["rooms"][r] = entry
    for other in COMPARED:
        across["all_rooms"][f"multi_minus_{other}"] = paired(pooled["multi"], pooled[other])
    out["across_seeds"] = across
with open(result + ".tmp", "w") as f:
    json.dump(out, f, indent=1)
os.replace(result + ".tmp", result)
# A short table on stdout.
for seed, e in out["seeds"].items():
    print(f"seed {seed}: T60 % / C50 dB / EDT s / STFT  (lower is better)")
    for r, x in e["rooms"].items():
        for name, v in (("single", x["single"]["neraf"]),
                        ("single long", x["single_long"]["neraf"]), ("multi", x["multi"]["neraf"]),
                        ("multi zeros", x["multi_grid_zeros"]), ("multi none", x["multi_grid_none"]),
                        ("linear", x["multi"]["linear"])):
            print(f"  {r:11s} {name:12s} " + "  ".join(f"{v[m]:.4g}" for m in METRICS))
        for name in ("paired_multi_minus_single", "paired_multi_minus_single_long",
                     "paired_multi_minus_zeros", "paired_multi_minus_none"):
            p = x[name]
            print(f"  {r:11s} {name:26s} " + "  ".join(
                f"{p[m]['mean_difference']:+.4g}±{(p[m]['standard_error'] or float('nan')):.2g}" for m in METRICS))
if "across_seeds" in out:
    print(f"over seeds {' '.join(seeds)}: multi - other, per-RIR difference of the seed-averaged errors")
    for r, x in list(out["across_seeds"]["rooms"].items()) + [("all", out["across_seeds"]["all_rooms"])]:
        for other in COMPARED:
            p = x[f"multi_minus_{other}"]
            p = p.get("paired_per_rir", p)
            print(f"  {r:11s} vs {other:12s} " + "  ".join(
                f"{p[m]['mean_difference']:+.4g}±{(p[m]['standard_error'] or float('nan')):.2g}" for m in METRICS))
print("wrote", result)
EOF
