#!/usr/bin/env bash
# The cpu preset on the 20k-RIR apartment (issue 14 §1): `neraf train` with its defaults (joint,
# schedule scaled to the data), timed with its peak memory, then `neraf eval` on the held-out
# split and on new microphone positions, with the nearest and linear baselines.
#   bench/scale_train.sh [OUT_JSON]      default build/bench/scale_train.json
#   WORK=build/bench/scale_train SEED=42 NOVEL_EVERY=10 bench/scale_train.sh
#   TRAIN_ARGS="--grid-features local" ...   extra `neraf train` flags (recorded in the JSON)
#   NERAF=build/x/neraf ...                  another binary (a copy keeps a rebuild from relinking it mid-run)
# New positions: `neraf synth --preset apartment --mics random` (500 positions x 4 headings x 14
# sources = 28,000 RIRs), every NOVEL_EVERY-th of them scored (eval scores every RIR it is given).
# Steps already done in WORK (data, a finished run with its train.time) are reused. Needs GNU
# time (Debian package `time`), about 12 GB of disk, and an otherwise idle machine for the timing.
set -euo pipefail
cd "$(dirname "$0")/.."
NERAF=${NERAF:-build/neraf}
WORK=${WORK:-build/bench/scale_train}
OUT=${1:-build/bench/scale_train.json}
SEED=${SEED:-42}
NOVEL_EVERY=${NOVEL_EVERY:-10}
read -r -a TRAIN_ARGS <<<"${TRAIN_ARGS:-}"
[ -x /usr/bin/time ] || { echo "bench/scale_train.sh: needs GNU time (apt-get install time)" >&2; exit 1; }
[ -x "$NERAF" ] || { echo "bench/scale_train.sh: build neraf first (scripts/build.sh)" >&2; exit 1; }
mkdir -p "$WORK"
load_before=$(cut -d' ' -f1-3 /proc/loadavg)

[ -f "$WORK/apartment/synth_info.json" ] ||
  $NERAF synth --preset apartment --out "$WORK/apartment" --seed 1 --force --quiet
[ -f "$WORK/apartment_novel/synth_info.json" ] ||
  $NERAF synth --preset apartment --mics random --out "$WORK/apartment_novel" --seed 2 \
    --gain-from "$WORK/apartment" --force --quiet

# Every NOVEL_EVERY-th new-position RIR, as a dataset of its own (files symlinked).
novel="$WORK/apartment_novel_subset"
rm -rf "$novel"
mkdir -p "$novel/metadata_AudioNeRF"
for f in binaural_rirs images transforms.json metadata scene.json synth_info.json; do
  ln -s "$(realpath "$WORK/apartment_novel/$f")" "$novel/$f"
done
python3 - "$WORK/apartment_novel/metadata_AudioNeRF/split.json" "$NOVEL_EVERY" \
  >"$novel/metadata_AudioNeRF/split.json" <<'EOF'
import json, sys
split, every = json.load(open(sys.argv[1])), int(sys.argv[2])
json.dump({k: v[::every] for k, v in split.items()}, sys.stdout)
EOF

if [ ! -f "$WORK/train.time" ]; then
  /usr/bin/time -f '%M %e' -o "$WORK/train.time.tmp" \
    $NERAF train --data "$WORK/apartment" --out "$WORK/run" --seed "$SEED" --force "${TRAIN_ARGS[@]}" \
    2>&1 | tr '\r' '\n' | grep -v '^train ' >"$WORK/train.log"
  mv "$WORK/train.time.tmp" "$WORK/train.time"
fi
/usr/bin/time -f '%M %e' -o "$WORK/eval.time" \
  $NERAF eval --run "$WORK/run" --novel-data "$novel" --no-images --json "$WORK/eval.json" --quiet

mkdir -p "$(dirname "$OUT")"
python3 - "$WORK" "$OUT" "$load_before" "$NOVEL_EVERY" "${TRAIN_ARGS[*]}" <<'EOF'
import datetime, json, os, re, sys
work, out, load_before, every, train_args = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
def timed(name):
    kb, s = open(os.path.join(work, name)).read().split()
    return {"peak_rss_mib": round(int(kb) / 1024), "seconds": float(s)}
config = json.load(open(os.path.join(work, "run", "config.json")))
data = json.load(open(os.path.join(work, "run", "data.json")))
ev = json.load(open(os.path.join(work, "eval.json")))
log = open(os.path.join(work, "train.log")).read()
fitted = re.search(r"cpu preset: (\d+) training \(RIR, frame\) slices, so (\d+) audio steps instead of (\d+)", log)
cpu = open("/proc/cpuinfo").read()
model = re.search(r"model name\s*:\s*(.*)", cpu).group(1)
def strip(a):  # the tables, without per-RIR file names
    return {k: v for k, v in a.items() if k not in ("per_rir_csv", "grid", "data")}
audio = ev["audio"]
result = {
    "command": "bench/scale_train.sh (SEED=%s, NOVEL_EVERY=%d%s)" % (
        config["seed"], every, ", TRAIN_ARGS=\"%s\"" % train_args if train_args else ""),
    "what": "neraf train --data apartment (cpu preset defaults: joint, schedule scaled to the data), "
            "then neraf eval --novel-data (every %d-th RIR of a 28,000-RIR random-position set)" % every,
    "machine": "%s, %d cores, %.0f GiB" % (model, os.cpu_count(),
               os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30),
    "date": datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"),
    "load_before": load_before,
    "load_after": " ".join(open("/proc/loadavg").read().split()[:3]),
    "steps": config["steps"],
    "audio_start_step": config["audio"]["start_step"],
    "train_rirs": data["audio"]["num_train"], "test_rirs": data["audio"]["num_test"],
    "frames_per_rir": data["audio"]["max_len"],
    "fit": None if not fitted else {"train_slices": int(fitted.group(1)),
                                    "audio_steps": int(fitted.group(2)),
                                    "audio_steps_unscaled": int(fitted.group(3))},
    "train": timed("train.time"),
    "eval": timed("eval.time"),
    "vision": {k: ev["vision"][k] for k in ("psnr", "ssim", "n_views")} if "vision" in ev else None,
    "held_out": strip(audio),
    "novel": strip(audio["novel"]),
}
result["held_out"].pop("novel", None)
open(out + ".tmp", "w").write(json.dumps(result, indent=2) + "\n")
os.replace(out + ".tmp", out)
print("wrote", out)
for split in ("held_out", "novel"):
    a = result[split]
    print(split, "n =", a["neraf"]["n_rirs"])
    for m in ("neraf", "nearest", "linear"):
        print("  %-8s T60 %.2f %%  C50 %.3f dB  EDT %.4f s" % (m, a[m]["t60_error_pct"], a[m]["c50_error_db"], a[m]["edt_error_s"]))
    for b in ("nearest", "linear"):
        p = a["paired"][b]
        print("  neraf - %-7s" % b, "  ".join("%s %+.4f ± %.4f" % (k, v["mean_difference"], v["standard_error"]) for k, v in p.items()))
EOF
