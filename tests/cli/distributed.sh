#!/usr/bin/env bash
# Data-parallel training over c10d/Gloo on 127.0.0.1 (train/distributed.h), driven as a user
# would: neraf launch with 2 processes, resume with another world size, a rank killed mid-run
# (the survivor stops with a clear error within the timeout; the newest checkpoint loads),
# Ctrl-C to launch, and bad distributed input (one error line each, bounded in time, no run
# folder damaged).
# (Parameter equality with one process: tests/train/distributed_test.cpp.)
# Usage: distributed.sh <path to neraf> <assets dir>
set -u
NERAF=$1
ASSETS=$2
source "$(dirname "$0")/lib.sh"

free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])'; }
one_error_line() {  # one_error_line FILE PATTERN
  [ "$(grep -c '^error' "$1")" -eq 1 ] || fail "expected one error line in $(basename "$1"): $(cat "$1")"
  expect_in "$1" "$2"
}

S=$TMP/scene
expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --out "$S" --seed 3 --quiet
small=(--audio-start-step 2 --rays 256 --threads 1 --quiet)

# 1. neraf launch: 2 local ranks; rank 0 alone writes the run folder.
R=$TMP/run
expect_exit 0 "$NERAF" launch -n 2 -- train --data "$S" --out "$R" --steps 6 --save-every 3 "${small[@]}"
expect_in "$TMP/out" "trained steps 0..6"
expect_in "$TMP/out" "all-reduce"
expect_file "$R/config.json"
expect_file "$R/data.json"
expect_file "$R/checkpoints/step-000000006.pt"
expect_file "$R/checkpoints/step-000000003.pt"
grep -q "^error" "$TMP/err" && fail "launch printed an error: $(cat "$TMP/err")"

# 2. Resume with another world size: 1 process, then 2 again (rank 0 sends the checkpoint).
expect_exit 0 "$NERAF" train --out "$R" --resume --steps 8 --threads 1 --quiet
expect_in "$TMP/out" "trained steps 6..8"
expect_exit 0 "$NERAF" launch -n 2 -- train --out "$R" --resume --steps 10 --threads 1 --quiet
expect_in "$TMP/out" "trained steps 8..10"
expect_file "$R/checkpoints/step-000000010.pt"
expect_exit 0 "$NERAF" render rir --run "$R" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --out "$TMP/r.wav"

# 3. A rank killed mid-run: the survivor stops within the timeout with one error line naming
# the failure; the newest checkpoint is intact and training resumes from it.
K=$TMP/killed P=$(free_port)
dist=(--world-size 2 --master "127.0.0.1:$P" --dist-timeout 5)
"$NERAF" train --data "$S" --out "$K" --steps 100000 --save-every 2 "${small[@]}" "${dist[@]}" \
  --rank 0 >"$TMP/k0.out" 2>"$TMP/k0.err" &
r0=$!
"$NERAF" train --data "$S" --out "$K" --steps 100000 --save-every 2 "${small[@]}" "${dist[@]}" \
  --rank 1 >"$TMP/k1.out" 2>"$TMP/k1.err" &
r1=$!
for ((i = 0; i < 600; ++i)); do  # until the second checkpoint (60 s at most)
  [ -f "$K/checkpoints/step-000000004.pt" ] && break
  sleep 0.1
done
kill -KILL "$r1"
t0=$(date +%s.%N)
wait "$r0"
rc=$?
t1=$(date +%s.%N)
{ wait "$r1"; } 2>/dev/null
echo "rank 0 stopped $(python3 -c "print(round($t1 - $t0, 2))") s after rank 1 was killed"
[ "$rc" -eq 1 ] || fail "the surviving rank 0 exited $rc after rank 1 was killed: $(cat "$TMP/k0.err")"
one_error_line "$TMP/k0.err" "distributed training, rank 0 of 2: .* failed"
python3 -c "import sys; sys.exit(0 if $t1 - $t0 < 15 else 1)" ||
  fail "rank 0 took $(python3 -c "print(round($t1 - $t0, 1))") s to stop (timeout 5 s)"
expect_exit 0 "$NERAF" train --out "$K" --resume --steps 6 --threads 1 --quiet
grep -q "damaged" "$TMP/err" && fail "a damaged checkpoint after the kill: $(cat "$TMP/err")"
expect_file "$K/checkpoints/step-000000006.pt"

# 4. Ctrl-C (SIGINT) to launch: forwarded once; every rank stops after the same step, rank 0
# saves it, exit 130 (as train's own after an interrupt).
I=$TMP/interrupted
"$NERAF" launch -n 2 -- train --data "$S" --out "$I" --steps 100000 --save-every 100000 \
  "${small[@]}" >"$TMP/i.out" 2>"$TMP/i.err" &
li=$!
for ((i = 0; i < 600; ++i)); do [ -f "$I/config.json" ] && break; sleep 0.1; done
sleep 2
kill -INT "$li"
wait "$li"
rc=$?
[ "$rc" -eq 130 ] || fail "launch exited $rc after Ctrl-C, expected 130: $(cat "$TMP/i.err")"
expect_in "$TMP/i.err" "interrupted: training stopped at step"
[ "$(find "$I/checkpoints" -name 'step-*[0-9].pt' | wc -l)" -eq 1 ] ||
  fail "expected the one checkpoint of the interrupt: $(ls "$I/checkpoints")"

# 5. Bad distributed input: one error line each, within the timeout, no run folder left.
B=$TMP/bad
expect_exit 1 "$NERAF" train --data "$S" --out "$B" --world-size 2 --rank 2
one_error_line "$TMP/err" "--rank 2: must be below --world-size 2"
expect_exit 1 "$NERAF" train --data "$S" --out "$B" --rank 1
one_error_line "$TMP/err" "--rank: only with --world-size"
expect_exit 1 "$NERAF" train --data "$S" --out "$B" --world-size 2 --master nohost
one_error_line "$TMP/err" "--master nohost: expected HOST:PORT"
expect_exit 2 "$NERAF" train --data "$S" --out "$B" --world-size 2 --dist-timeout 0
expect_exit 1 "$NERAF" launch -n 2 -- train --data "$S" --out "$B" --rank 1
one_error_line "$TMP/err" "launch: --rank is set by launch"
expect_exit 1 "$NERAF" launch -n 2 -- info "$S"
one_error_line "$TMP/err" "expected '-- train"
# An unreachable master (nobody listens): rank 1 gives up after --dist-timeout.
P=$(free_port)
t0=$(date +%s)
expect_exit 1 "$NERAF" train --data "$S" --out "$B" --world-size 2 --rank 1 \
  --master "127.0.0.1:$P" --dist-timeout 2 --quiet
one_error_line "$TMP/err" "rank 1 cannot reach rank 0 within --dist-timeout 2 s"
[ $(($(date +%s) - t0)) -le 20 ] || fail "the unreachable master took $(($(date +%s) - t0)) s"
# A port in use (another rank 0 listens there): the second rank 0 is refused at once.
"$NERAF" train --data "$S" --out "$TMP/first" --world-size 2 --rank 0 --master "127.0.0.1:$P" \
  --dist-timeout 20 --quiet >/dev/null 2>&1 &
first=$!
sleep 1
expect_exit 1 "$NERAF" train --data "$S" --out "$B" --world-size 2 --rank 0 \
  --master "127.0.0.1:$P" --dist-timeout 2 --quiet
one_error_line "$TMP/err" "cannot listen on port $P"
kill "$first" 2>/dev/null
wait "$first" 2>/dev/null
# World sizes that disagree: both ranks stop with the same line.
P=$(free_port)
"$NERAF" train --data "$S" --out "$B" --world-size 2 --rank 0 --master "127.0.0.1:$P" \
  --dist-timeout 10 --quiet >"$TMP/w0.out" 2>"$TMP/w0.err" &
w0=$!
expect_exit 1 "$NERAF" train --data "$S" --out "$B" --world-size 3 --rank 1 \
  --master "127.0.0.1:$P" --dist-timeout 10 --quiet
one_error_line "$TMP/err" "world-size differs between the ranks: rank 0 has 2, rank 1 has 3"
wait "$w0"
[ $? -eq 1 ] || fail "rank 0 of a disagreeing world size did not exit 1"
one_error_line "$TMP/w0.err" "world-size differs between the ranks"
# Flags that disagree (another seed on rank 1): refused before training, naming the setting.
P=$(free_port)
"$NERAF" train --data "$S" --out "$B" --world-size 2 --rank 0 --master "127.0.0.1:$P" \
  --dist-timeout 10 "${small[@]}" >"$TMP/f0.out" 2>"$TMP/f0.err" &
f0=$!
expect_exit 1 "$NERAF" train --data "$S" --out "$B" --world-size 2 --rank 1 \
  --master "127.0.0.1:$P" --dist-timeout 10 "${small[@]}" --seed 7
one_error_line "$TMP/err" "training config differs between rank 0 and rank 1 (config.seed)"
wait "$f0"
[ $? -eq 1 ] || fail "rank 0 with disagreeing flags did not exit 1"
[ -e "$B" ] && fail "a refused distributed run left $B behind"
# A global batch that does not split over the ranks.
expect_exit 1 "$NERAF" launch -n 2 -- train --data "$S" --out "$B" --rays 255 --threads 1 --quiet
expect_in "$TMP/err" "launch -n 2: the batch of 255 rays (--rays) does not split evenly over 2"
[ -e "$B" ] && fail "a refused distributed run left $B behind"
# More threads in all than cores is warned about (launch alone gives each cores / N).
expect_exit 1 "$NERAF" launch -n 2 -- train --data "$S" --out "$B" --rays 255 --threads "$(nproc)" \
  --quiet
expect_in "$TMP/err" "warning: launch: 2 processes x $(nproc) threads"

finish distributed
