#!/usr/bin/env bash
# SIGKILL at random moments of a training run, then --resume, KILLS times; then the run finishes;
# then a full disk during a checkpoint write and during synth.
# Every step writes a checkpoint (--save-every 1), so many kills land inside a checkpoint write.
# Checks: every restart succeeds and never meets a damaged checkpoint, the orphaned temporary
# files of a kill are gone after the next start, and the finished run renders exactly the RIR of
# an uninterrupted run with the same seed and thread count (nothing lost, nothing changed).
# Usage: kill_resume.sh <path to neraf> <assets dir> [KILLS (default 20)]
set -u
NERAF=$1
ASSETS=$2
KILLS=${3:-20}
source "$(dirname "$0")/lib.sh"

S=$TMP/scene R=$TMP/run
expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --out "$S" --seed 3 --quiet
settings=(--steps 40 --audio-start-step 2 --rays 256 --threads 1 --save-every 1 --keep 3 --quiet)
new_run=(train --data "$S" --out "$R" "${settings[@]}")
resume=(train --out "$R" --resume --threads 1 --save-every 1 --keep 3 --quiet)
expect_exit 0 "$NERAF" train --data "$S" --out "$TMP/reference" "${settings[@]}"

temporaries() { find "$R" -name '*.tmp-*' 2>/dev/null | wc -l; }
RANDOM=12345  # the same kill times every run
orphans=0 in_write=0 restarts=0 steps=() orphaned=() last_step=
for ((k = 1; k <= KILLS; ++k)); do
  if [ -f "$R/config.json" ]; then cmd=("${resume[@]}"); else cmd=("${new_run[@]}"); fi
  "$NERAF" "${cmd[@]}" >"$TMP/out" 2>"$TMP/err" &
  pid=$!
  # 0.3–3.3 s: some kills hit start-up, most hit training steps and checkpoint writes.
  sleep "$((RANDOM % 3)).$((RANDOM % 1000 + 300))"
  if ! kill -0 "$pid" 2>/dev/null; then
    wait "$pid"
    echo "run finished before kill $k"
    break
  fi
  kill -KILL "$pid"
  wait "$pid" 2>/dev/null
  ((++restarts))
  grep -q "damaged" "$TMP/err" && fail "restart $k met a damaged checkpoint: $(cat "$TMP/err")"
  grep -q "^error" "$TMP/err" && fail "restart $k failed: $(cat "$TMP/err")"
  newest=$(find "$R/checkpoints" -name 'step-*[0-9].pt' 2>/dev/null | sort | tail -1)
  step=${newest:+$((10#$(basename "$newest" .pt | cut -d- -f2)))}
  # A restart that got as far as a new checkpoint was past its start-up, where it removes what
  # the kill before it left.
  if [ -n "$step" ] && [ "$step" != "$last_step" ]; then
    for f in "${orphaned[@]}"; do
      [ -e "$f" ] && fail "restart $k (now at step $step) left $f of the kill before it"
    done
  fi
  steps+=("${step:-none}")
  last_step=$step
  mapfile -t orphaned < <(find "$R" -name '*.tmp-*' 2>/dev/null)
  now=${#orphaned[@]}
  orphans=$((orphans + now))
  [ "$now" -gt 0 ] && ((++in_write))
done
# The last restart runs to the end (and calibrates).
expect_exit 0 "$NERAF" "${resume[@]}"
grep -q "damaged" "$TMP/err" && fail "the final resume met a damaged checkpoint: $(cat "$TMP/err")"
[ "$(temporaries)" -eq 0 ] || fail "temporary files left after the final resume: $(find "$R" -name '*.tmp-*')"
expect_file "$R/checkpoints/step-000000040.pt"
expect_file "$R/checkpoints/step-000000040.calibration.pt"
[ "$(find "$R/checkpoints" -name 'step-*[0-9].pt' | wc -l)" -le 3 ] || fail "more than --keep 3 checkpoints"

for run in reference run; do
  expect_exit 0 "$NERAF" render rir --run "$TMP/$run" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --yaw 90 \
    --out "$TMP/$run.wav"
done
cmp -s "$TMP/reference.wav" "$TMP/run.wav" ||
  fail "the killed and resumed run renders another RIR than the uninterrupted one"
# A full disk during a checkpoint write (simulated with a file size limit: writes past it fail
# with EFBIG, as on a full disk with ENOSPC): one error line, exit 1, no temporary file, and the
# checkpoints before it intact.
(trap '' XFSZ; ulimit -f 20000; exec "$NERAF" train --out "$R" --resume --steps 41 --quiet) \
  >"$TMP/out" 2>"$TMP/err"
rc=$?
[ "$rc" -eq 1 ] || fail "a full disk during a checkpoint write exited $rc: $(tail -c 300 "$TMP/err")"
expect_in "$TMP/err" "step-000000041.pt: write failed"
[ "$(grep -c '^error' "$TMP/err")" -eq 1 ] || fail "expected one error line: $(cat "$TMP/err")"
grep -q "terminate called" "$TMP/err" && fail "the full disk aborted the process: $(cat "$TMP/err")"
[ "$(temporaries)" -eq 0 ] || fail "the failed write left $(find "$R" -name '*.tmp-*')"
[ -e "$R/checkpoints/step-000000041.pt" ] && fail "a checkpoint was written past the disk limit"
expect_exit 0 "$NERAF" train --out "$R" --resume --steps 41 --quiet
grep -q "damaged" "$TMP/err" && fail "the resume after a full disk met a damaged checkpoint"
# The same for a dataset: a synth that runs out of space leaves nothing behind.
(trap '' XFSZ; ulimit -f 50; exec "$NERAF" synth --preset demo --layout soundspaces \
  --out "$TMP/full" --seed 3 --quiet) >"$TMP/out" 2>"$TMP/err"
rc=$?
[ "$rc" -eq 1 ] || fail "synth on a full disk exited $rc: $(tail -c 300 "$TMP/err")"
[ -e "$TMP/full" ] && fail "synth on a full disk left $TMP/full"
[ "$(find "$TMP" -maxdepth 1 -name '.full.tmp-*' | wc -l)" -eq 0 ] || fail "synth left a temporary folder"

# Ctrl-C: training saves a checkpoint and exits 130 ("interrupted: ..."), resumable. A synth
# stopped by SIGTERM deletes its temporary folder and ends as the signal would (143 in the
# shell), leaving nothing. (SIGINT for it is not tried: a background job of a script starts with
# SIGINT ignored, and neraf keeps an ignored signal ignored.)
"$NERAF" train --out "$R" --resume --steps 100000 --threads 1 --save-every 1000 --quiet \
  >"$TMP/out" 2>"$TMP/err" &
pid=$!
sleep 3
kill -INT "$pid"
wait "$pid"
rc=$?
[ "$rc" -eq 130 ] || fail "train after Ctrl-C exited $rc, expected 130: $(tail -c 300 "$TMP/err")"
expect_in "$TMP/err" "^interrupted: training stopped at step"
[ "$(temporaries)" -eq 0 ] || fail "Ctrl-C during training left $(find "$R" -name '*.tmp-*')"
newest=$(find "$R/checkpoints" -name 'step-*[0-9].pt' | sort | tail -1)
[ "$(basename "$newest")" != "step-000000041.pt" ] || fail "Ctrl-C saved no checkpoint"
expect_exit 0 "$NERAF" train --out "$R" --resume --steps "$((10#$(basename "$newest" .pt | cut -d- -f2) + 1))" --quiet
"$NERAF" synth --preset demo --layout soundspaces --mics random --mic-count 100 \
  --out "$TMP/stopped" --seed 3 --quiet >"$TMP/out" 2>"$TMP/err" &
pid=$!
sleep 2
kill -TERM "$pid"
wait "$pid"
rc=$?
[ "$rc" -eq 143 ] || fail "synth after SIGTERM exited $rc, expected 143"
[ -e "$TMP/stopped" ] && fail "synth stopped by SIGTERM left $TMP/stopped"
[ "$(find "$TMP" -maxdepth 1 -name '.stopped.tmp-*' | wc -l)" -eq 0 ] ||
  fail "synth stopped by SIGTERM left its temporary folder"

echo "kill_resume: $restarts kills ($in_write during a checkpoint write, $orphans orphaned temporary" \
  "files, all removed by the next start); newest checkpoint after each kill: ${steps[*]:-none}"
finish kill_resume
