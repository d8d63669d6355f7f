#!/usr/bin/env bash
# Bad flag values on every command: each must exit 1 or 2 within 20 s, print exactly one
# "error:" line that names the flag (or the file), and leave no output behind. Plus the positive
# side of the feature-cache flags (--cache-dir puts the cache there, fp16 halves it, eval finds
# the run's cache).
# Usage: bad_flags.sh <path to neraf> <assets dir>
set -u
NERAF=$1
ASSETS=$2
source "$(dirname "$0")/lib.sh"

WORK="$TMP/work"  # where every refused command would write; must stay empty
mkdir -p "$WORK"
FIX="$TMP/fixtures"
mkdir -p "$FIX"
WAV="$ASSETS/real/rir_clap.wav"
DRY="$ASSETS/real/castanets_dry.wav"
classes=0

# bad NAME CMD...: CMD must fail cleanly (exit 1 or 2, in time, one error line naming NAME,
# nothing written under $WORK).
bad() {
  local name=$1; shift
  classes=$((classes + 1))
  timeout 20 "$@" >"$TMP/out" 2>"$TMP/err"
  local got=$?
  local what="'${*#"$NERAF" }'"
  if [ "$got" -eq 124 ]; then
    fail "$what: still running after 20 s"
  elif [ "$got" -ne 1 ] && [ "$got" -ne 2 ]; then
    fail "$what: exited $got, expected 1 or 2; stderr: $(tail -c 300 "$TMP/err")"
  fi
  local n
  n=$(grep -c '^error:' "$TMP/err")
  [ "$n" -eq 1 ] || fail "$what: $n error lines, expected 1: $(head -c 400 "$TMP/err")"
  grep '^error:' "$TMP/err" | grep -qF -- "$name" ||
    fail "$what: the error does not name '$name': $(grep '^error:' "$TMP/err" | head -c 300)"
  if grep -q "bad_alloc\|can't allocate\|terminate called" "$TMP/err"; then
    fail "$what: raw allocator text: $(head -c 300 "$TMP/err")"
  fi
  if [ -n "$(ls -A "$WORK")" ]; then
    fail "$what: left output behind: $(ls -A "$WORK" | head -5 | tr '\n' ' ')"
    rm -rf "${WORK:?}"/* "$WORK"/.[!.]* 2>/dev/null
  fi
}

# --- fixtures: scene files with absurd sizes ------------------------------------------------
echo '{"size": [4, 3, 5], "microphones": {"grid": {"spacing_m": 1e-6}}}' >"$FIX/spacing.json"
echo '{"size": [1e9, 3, 4]}' >"$FIX/huge_room.json"
echo '{"acoustics": {"max_order": 61}}' >"$FIX/order.json"
python3 - "$FIX/boxes.json" <<'PY'
import json, sys
boxes = [{"center": [5, 0.05, 5], "size": [0.1, 0.1, 0.1]} for _ in range(20000)]
json.dump({"size": [10, 3, 10], "furniture": boxes}, open(sys.argv[1], "w"))
PY
echo '{"keyframes": []}' >"$FIX/path.json"

# --- integers: overflow, negative, fractions, text, out of range ----------------------------
bad --steps "$NERAF" train --data "$FIX" --out "$WORK/run" --steps 99999999999999999999
bad --steps "$NERAF" train --data "$FIX" --out "$WORK/run" --steps 0
bad --steps "$NERAF" train --data "$FIX" --out "$WORK/run" --steps 1.5
bad --steps "$NERAF" train --data "$FIX" --out "$WORK/run" --steps many
bad --steps "$NERAF" train --data "$FIX" --out "$WORK/run" --steps 0x10
bad --audio-start-step "$NERAF" train --data "$FIX" --out "$WORK/run" --audio-start-step -5
bad --rays "$NERAF" train --data "$FIX" --out "$WORK/run" --rays 0
bad --rays "$NERAF" train --data "$FIX" --out "$WORK/run" --rays 1e10
bad --max-views "$NERAF" eval --run "$FIX" --json "$WORK/e.json" --max-views -3
bad --max-rirs "$NERAF" eval --run "$FIX" --json "$WORK/e.json" --max-rirs 1e30
bad --max-problems "$NERAF" info "$FIX" --max-problems -1
bad --t60-sample "$NERAF" info "$FIX" --t60-sample 0
bad --frame "$NERAF" render view --run "$FIX" --frame -1 --out "$WORK/v.png"
bad --frame "$NERAF" render view --run "$FIX" --frame 1e99 --out "$WORK/v.png"
bad --block "$NERAF" render trajectory --run "$FIX" --path "$FIX/path.json" --in "$DRY" \
  --out "$WORK/w.wav" --block 99999999999
bad --mic-count "$NERAF" synth --preset demo --mics random --mic-count 0 --out "$WORK/ds"
bad --mic-count "$NERAF" synth --preset demo --mics random --mic-count 2000000 --out "$WORK/ds"

# --- seeds: negative and overflowing values are errors, not 2^64 - 1 -----------------------
bad --seed "$NERAF" train --data "$FIX" --out "$WORK/run" --seed -1
bad --seed "$NERAF" train --data "$FIX" --out "$WORK/run" --seed 1e23
bad --seed "$NERAF" synth --preset demo --out "$WORK/ds" --seed 18446744073709551616
bad --seed "$NERAF" render rir --run "$FIX" --mic 1,1,1 --src 2,1,1 --out "$WORK/r.wav" --seed -5
bad --seed "$NERAF" render trajectory --run "$FIX" --path "$FIX/path.json" --in "$DRY" \
  --out "$WORK/w.wav" --seed 3.5

# --- reals: NaN, infinity, out of range, text -----------------------------------------------
bad --audio-fraction "$NERAF" train --data "$FIX" --out "$WORK/run" --audio-fraction nan
bad --audio-fraction "$NERAF" train --data "$FIX" --out "$WORK/run" --audio-fraction 0
bad --decay-loss "$NERAF" train --data "$FIX" --out "$WORK/run" --decay-loss inf
bad --decay-loss "$NERAF" train --data "$FIX" --out "$WORK/run" --decay-loss -1
bad --position-max-freq-exp "$NERAF" train --data "$FIX" --out "$WORK/run" --position-max-freq-exp nan
bad --position-max-freq-exp "$NERAF" train --data "$FIX" --out "$WORK/run" --position-max-freq-exp 9
bad --yaw "$NERAF" render rir --run "$FIX" --mic 1,1,1 --src 2,1,1 --out "$WORK/r.wav" --yaw nan
bad --yaw "$NERAF" render rir --run "$FIX" --mic 1,1,1 --src 2,1,1 --out "$WORK/r.wav" --yaw 1e6
bad --src-yaw "$NERAF" auralize --run "$FIX" --mic 1,1,1 --src 2,1,1 --in "$DRY" \
  --out "$WORK/a.wav" --src-yaw abc
bad --spacing "$NERAF" render loudness --run "$FIX" --src 1,1,1 --out "$WORK/l.png" --spacing 0
bad --spacing "$NERAF" render loudness --run "$FIX" --src 1,1,1 --out "$WORK/l.png" \
  --spacing 1e-300
bad --height "$NERAF" render loudness --run "$FIX" --src 1,1,1 --out "$WORK/l.png" --height inf
bad --rate "$NERAF" render trajectory --run "$FIX" --path "$FIX/path.json" --in "$DRY" \
  --out "$WORK/w.wav" --rate 0
bad --fps "$NERAF" render trajectory --run "$FIX" --path "$FIX/path.json" --in "$DRY" \
  --out "$WORK/w.wav" --fps nan

# --- threads: at most 4 x the cores, and at least 1 -----------------------------------------
bad --threads "$NERAF" train --data "$FIX" --out "$WORK/run" --threads 100000
# Data-parallel training (train/distributed.h; the network cases: tests/cli/distributed.sh).
bad --world-size "$NERAF" train --data "$FIX" --out "$WORK/run" --world-size 0
bad --world-size "$NERAF" train --data "$FIX" --out "$WORK/run" --world-size 1e9
bad --rank "$NERAF" train --data "$FIX" --out "$WORK/run" --world-size 2 --rank -1
bad --rank "$NERAF" train --data "$FIX" --out "$WORK/run" --world-size 2 --rank 5
bad --dist-timeout "$NERAF" train --data "$FIX" --out "$WORK/run" --world-size 2 --dist-timeout nan
bad --master "$NERAF" train --data "$FIX" --out "$WORK/run" --world-size 2 --master host:99999
bad --dist-overlap "$NERAF" train --data "$FIX" --out "$WORK/run" --world-size 2 --dist-overlap maybe
bad --nproc "$NERAF" launch -n 0 -- train --data "$FIX" --out "$WORK/run"
bad --nproc "$NERAF" launch -n 1000 -- train --data "$FIX" --out "$WORK/run"
bad --master-port "$NERAF" launch -n 2 --master-port 70000 -- train --data "$FIX" --out "$WORK/run"
bad --grace "$NERAF" launch -n 2 --grace -1 -- train --data "$FIX" --out "$WORK/run"
bad --threads "$NERAF" eval --run "$FIX" --json "$WORK/e.json" --threads 0
bad --threads "$NERAF" synth --preset demo --out "$WORK/ds" --threads -1
bad --threads "$NERAF" render rir --run "$FIX" --mic 1,1,1 --src 2,1,1 --out "$WORK/r.wav" \
  --threads 100000
bad --threads "$NERAF" render view --run "$FIX" --frame 0 --out "$WORK/v.png" --threads 1e9
grep '^error:' "$TMP/err" | grep -q "4 x the" || fail "--threads error does not state the cap"

# --- absurd sizes: refused before any memory or disk is used, with the estimate -------------
bad --mic-count "$NERAF" synth --preset demo --layout raf --mics random --mic-count 1000000 \
  --out "$WORK/ds"
grep '^error:' "$TMP/err" | grep -q "GB.*limits are" || fail "synth size error has no estimate"
bad "$FIX/spacing.json" "$NERAF" synth --scene "$FIX/spacing.json" --out "$WORK/ds"
grep -q "the limit is" "$TMP/err" || fail "grid spacing error has no limit"
bad "$FIX/huge_room.json" "$NERAF" synth --scene "$FIX/huge_room.json" --out "$WORK/ds"
bad "$FIX/boxes.json" "$NERAF" synth --scene "$FIX/boxes.json" --out "$WORK/ds"
bad "$FIX/order.json" "$NERAF" synth --scene "$FIX/order.json" --out "$WORK/ds"
bad --rays "$NERAF" train --data "$FIX" --out "$WORK/run" --rays 1e8
grep '^error:' "$TMP/err" | grep -q "GB of memory" || fail "--rays error has no memory estimate"
bad --mic-count "$NERAF" synth --preset demo --mics random --mic-count 1000000 --dry-run

# --- enums, missing and conflicting flags ---------------------------------------------------
bad --modality "$NERAF" train --data "$FIX" --out "$WORK/run" --modality sound
bad --preset "$NERAF" train --data "$FIX" --out "$WORK/run" --preset huge
bad --cache-precision "$NERAF" train --data "$FIX" --out "$WORK/run" --cache-precision fp8
bad --cache-precision "$NERAF" eval --run "$FIX" --json "$WORK/e.json" --cache-precision half
bad --cache-precision "$NERAF" calibrate --run "$FIX" --cache-precision fp8
bad --layout "$NERAF" synth --preset demo --out "$WORK/ds" --layout ambisonic
bad --variant "$NERAF" metrics --rir "$WAV" --variant bogus
bad --precision "$NERAF" export --run "$FIX" --out "$WORK/m.nrf" --precision fp64
bad --out "$NERAF" train --data "$FIX"
bad --json "$NERAF" eval --run "$FIX"
bad --in "$NERAF" auralize --rir "$WAV" --out "$WORK/a.wav"
bad "--resume and --force" "$NERAF" train --out "$WORK/run" --resume --force
mkdir -p "$TMP/resumable" && echo "{}" >"$TMP/resumable/config.json"  # flags are checked first
bad --cache-dir "$NERAF" train --out "$TMP/resumable" --resume --cache-dir "$WORK/cache"
bad "no run to resume" "$NERAF" train --out "$WORK/none" --resume --rays 128
bad --model "$NERAF" eval --run "$FIX" --model "$FIX/m.nrf" --json "$WORK/e.json"
bad --pred "$NERAF" metrics --rir "$WAV" --pred "$WAV" --gt "$WAV"
bad --scene "$NERAF" synth --preset demo --scene "$FIX/order.json" --out "$WORK/ds"
bad --mic-count "$NERAF" synth --preset demo --mic-count 5 --out "$WORK/ds"

[ "$classes" -ge 30 ] || fail "only $classes bad-flag cases"
echo "$classes bad-flag cases run"

# --- the feature-cache flags, for real: a 9-RIR room, one training step ----------------------
cat >"$FIX/tiny.json" <<'JSON'
{"name": "tiny", "size": [3, 2.5, 3],
 "microphones": {"grid": {"spacing_m": 1.0, "wall_margin_m": 0.5, "headings_deg": [0, 180]}},
 "sources": [{"position": [1.5, 1.2, 1.3]}],
 "cameras": {"train_count": 4, "eval_count": 2, "width": 16, "height": 16, "supersampling": 1},
 "acoustics": {"max_order": 2, "rir_length_s": 0.2}}
JSON
DATA="$TMP/tiny"
expect_exit 0 timeout 120 "$NERAF" synth --scene "$FIX/tiny.json" --out "$DATA" --quiet
train_tiny() {  # train_tiny RUN ARGS...: one joint step
  local run=$1; shift
  expect_exit 0 timeout 300 "$NERAF" train --data "$DATA" --out "$run" --steps 2 \
    --audio-start-step 0 --rays 256 --quiet "$@"
}
train_tiny "$TMP/run32" --cache-dir "$TMP/cache32"
ls "$TMP/cache32"/*.bin >/dev/null 2>&1 || fail "--cache-dir: no cache file in it"
ls "$DATA/.neraf_cache"/*.bin >/dev/null 2>&1 && fail "--cache-dir: a cache was still made in the dataset"
python3 - "$TMP/run32/config.json" "$TMP/cache32" <<'PY' || fail "config.json does not record the cache"
import json, sys
a = json.load(open(sys.argv[1]))["audio"]
assert a["cache_dir"] == sys.argv[2] and a["cache_precision"] == "fp32", a
PY
train_tiny "$TMP/run16" --cache-dir "$TMP/cache16" --cache-precision fp16
size32=$(stat -c %s "$TMP"/cache32/*.bin 2>/dev/null | head -1)
size16=$(stat -c %s "$TMP"/cache16/*.bin 2>/dev/null | head -1)
if [ -z "$size32" ] || [ -z "$size16" ]; then
  fail "missing cache files ($size32 / $size16)"
else
  # The values halve; the header and the per-RIR lengths do not.
  [ $((size16 * 10)) -lt $((size32 * 6)) ] || fail "fp16 cache $size16 B is not about half of $size32 B"
fi
# eval reads the run's recorded cache: no new cache anywhere else.
expect_exit 0 timeout 300 "$NERAF" eval --run "$TMP/run32" --json "$TMP/eval32.json" --skip-vision \
  --no-images --no-baselines --quiet
expect_file "$TMP/eval32.json"
[ "$(ls "$TMP/cache32" | wc -l)" -eq 1 ] || fail "eval made another cache: $(ls "$TMP/cache32")"
ls "$DATA/.neraf_cache"/*.bin >/dev/null 2>&1 && fail "eval ignored the run's --cache-dir"
# calibrate too.
expect_exit 0 timeout 300 "$NERAF" calibrate --run "$TMP/run32" --quiet
[ "$(ls "$TMP/cache32" | wc -l)" -eq 1 ] || fail "calibrate made another cache: $(ls "$TMP/cache32")"
ls "$DATA/.neraf_cache"/*.bin >/dev/null 2>&1 && fail "calibrate ignored the run's --cache-dir"
# ... and --cache-dir on eval puts it elsewhere.
expect_exit 0 timeout 300 "$NERAF" eval --run "$TMP/run32" --json "$TMP/eval_c.json" --skip-vision \
  --no-images --no-baselines --quiet --cache-dir "$TMP/cache_eval"
ls "$TMP/cache_eval"/*.bin >/dev/null 2>&1 || fail "eval --cache-dir: no cache file in it"

finish "bad-flags"
