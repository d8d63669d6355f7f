#!/usr/bin/env bash
# Peak resident memory of `neraf train` (audio) and `neraf eval` against the number of RIRs
# (issue 14): the `apartment` preset (23,016 binaural RIRs) cut to its first 5k, 10k and 20k RIRs
# (train and test split cut in proportion), each trained for the same number of steps on the
# frozen field of one short vision run.
#   bench/scale_memory.sh [OUT_JSON]      default build/bench/scale_memory.json
#   STEPS=300 SIZES="5000 10000 20000" bench/scale_memory.sh
# Needs GNU time (/usr/bin/time, Debian package `time`) and about 20 GB of disk under build/bench.
set -euo pipefail
cd "$(dirname "$0")/.."
NERAF=build/neraf
WORK=${WORK:-build/bench/scale_memory}
OUT=${1:-build/bench/scale_memory.json}
STEPS=${STEPS:-300}
SIZES=${SIZES:-"5000 10000 20000"}
[ -x /usr/bin/time ] || { echo "bench/scale_memory.sh: needs GNU time (apt-get install time)" >&2; exit 1; }
[ -x "$NERAF" ] || { echo "bench/scale_memory.sh: build neraf first (scripts/build.sh)" >&2; exit 1; }
mkdir -p "$WORK"
load_before=$(cut -d' ' -f1-3 /proc/loadavg)

if [ ! -f "$WORK/apartment/synth_info.json" ]; then
  /usr/bin/time -f '%M %e' -o "$WORK/synth.time" \
    $NERAF synth --preset apartment --out "$WORK/apartment" --seed 1 --force --quiet
fi

# A SoundSpaces-layout folder with the first n RIRs of the split (the files are symlinked).
make_subset() {
  local n=$1 dst=$2
  rm -rf "$dst"
  mkdir -p "$dst/metadata_AudioNeRF" "$dst/metadata"
  for f in binaural_rirs images transforms.json metadata/points.txt; do
    ln -s "$(realpath "$WORK/apartment/$f")" "$dst/$f"
  done
  python3 - "$WORK/apartment/metadata_AudioNeRF/split.json" "$n" \
    >"$dst/metadata_AudioNeRF/split.json" <<'EOF'
import json, sys
split = json.load(open(sys.argv[1]))
n, total = int(sys.argv[2]), len(split["train"]) + len(split["test"])
n_test = round(n * len(split["test"]) / total)
json.dump({"train": split["train"][: n - n_test], "test": split["test"][:n_test]}, sys.stdout)
EOF
}

# One short vision run gives every subset its (frozen) radiance field: they share the images.
if [ ! -d "$WORK/vision/checkpoints" ]; then
  $NERAF train --data "$WORK/apartment" --modality vision --steps 100 --out "$WORK/vision" --force --quiet
fi

rows=()
for n in $SIZES; do
  sub="$WORK/apartment_$n"
  make_subset "$n" "$sub"
  /usr/bin/time -f '%M %e' -o "$WORK/train_$n.time" \
    $NERAF train --data "$sub" --modality audio --vision-run "$WORK/vision" --steps "$STEPS" \
    --out "$WORK/run_$n" --force --quiet
  /usr/bin/time -f '%M %e' -o "$WORK/eval_$n.time" \
    $NERAF eval --run "$WORK/run_$n" --skip-vision --no-images --max-rirs 200 \
    --json "$WORK/eval_$n.json" --quiet >/dev/null
  cache=$(du -bL "$sub"/.neraf_cache/*.bin | awk '{s += $1} END {printf "%.0f", s}')
  read -r train_kb train_s <"$WORK/train_$n.time"
  read -r eval_kb eval_s <"$WORK/eval_$n.time"
  rows+=("{\"rirs\": $n, \"cache_bytes\": $cache, \"train_peak_rss_kb\": $train_kb, \"train_s\": $train_s, \"eval_peak_rss_kb\": $eval_kb, \"eval_s\": $eval_s}")
  rm -rf "$sub/.neraf_cache"  # several GB each
done

mkdir -p "$(dirname "$OUT")"
{
  printf '{\n  "command": "bench/scale_memory.sh (STEPS=%s)",\n' "$STEPS"
  printf '  "what": "peak RSS of neraf train --modality audio --steps %s (cpu preset, frozen field of a 100-step vision run; feature cache build and calibration included) and of neraf eval --skip-vision --max-rirs 200, on the apartment preset cut to n RIRs",\n' "$STEPS"
  printf '  "machine": "%s, %s cores, %s GiB",\n' "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')" \
    "$(nproc)" "$(awk '/MemTotal/ {printf "%.0f", $2 / 1048576}' /proc/meminfo)"
  printf '  "date": "%s",\n  "load_before": "%s",\n  "load_after": "%s",\n' "$(date -u +%FT%TZ)" \
    "$load_before" "$(cut -d' ' -f1-3 /proc/loadavg)"
  printf '  "sizes": [\n    %s\n  ]\n}\n' "$(IFS=,; echo "${rows[*]}" | sed 's/},{/},\n    {/g')"
} >"$OUT.tmp"
mv "$OUT.tmp" "$OUT"
echo "wrote $OUT"
cat "$OUT"
