#!/usr/bin/env bash
# Multi-scene acoustic training through the `neraf` program on tiny runs: two rooms of different
# size (demo, small_dead), a short vision run each, one audio run over both (one grid per scene,
# one acoustic field) → eval (per scene + mean, with a --grid zeros ablation) → resume (the same
# numbers as without the interruption) → export / render with --scene, and the bad inputs: a
# --vision-run count that does not match --data, a vision run of another scene, scenes of another
# layout (and sample rate), joint multi-scene. Not a quality check: a few steps only.
# Usage: multiscene.sh <path to neraf> <assets dir>
set -u
NERAF=$1
ASSETS=$2
source "$(dirname "$0")/lib.sh"

A=$TMP/demo B=$TMP/small_dead
expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --out "$A" --seed 3 --quiet
expect_exit 0 "$NERAF" synth --preset small_dead --out "$B" --seed 3 --quiet
for s in demo small_dead; do
  expect_exit 0 "$NERAF" train --data "$TMP/$s" --modality vision --steps 2 --rays 128 \
    --out "$TMP/v-$s" --quiet
done
VA=$TMP/v-demo VB=$TMP/v-small_dead
M=$TMP/multi
common=(--modality audio --steps 5 --save-every 3 --threads 1 --quiet)

# --- train over both scenes; data.json lists them, config.json their vision runs --------------
expect_exit 0 "$NERAF" train --data "$A" --vision-run "$VA" --data "$B" --vision-run "$VB" \
  --out "$M" "${common[@]}"
expect_file "$M/checkpoints/step-000000005.pt"
expect_file "$M/checkpoints/step-000000005.calibration.pt"
expect_in "$M/data.json" '"scenes"'
expect_in "$M/data.json" '"name": "small_dead"'
expect_in "$M/config.json" '"vision_runs"'
# Each scene keeps its own frames per RIR (the small room's are fewer) beside the run's common
# frames, to which its features are padded.
python3 - "$M/data.json" <<'EOF' || fail "data.json: the scenes' own frames are not recorded"
import json, sys
a = [s["audio"] for s in json.load(open(sys.argv[1]))["scenes"]]
assert a[0]["max_len"] == a[1]["max_len"] == a[0]["scene_frames"], a
assert 2 <= a[1]["scene_frames"] < a[1]["max_len"], a
EOF

# --- render and export name a scene; the two scenes differ -------------------------------------
expect_exit 1 "$NERAF" render rir --run "$M" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --yaw 90 \
  --out "$TMP/x.wav"
expect_in "$TMP/err" "multi-scene run (2 scenes: 0 demo, 1 small_dead); pick one with --scene"
expect_exit 1 "$NERAF" export --run "$M" --out "$TMP/x.nrf"
expect_in "$TMP/err" "--scene"
expect_exit 1 "$NERAF" export --run "$M" --out "$TMP/x.nrf" --scene kitchen
expect_in "$TMP/err" "--scene kitchen: .* has no such scene; its scenes are 0 demo, 1 small_dead"
expect_exit 0 "$NERAF" export --run "$M" --out "$TMP/demo.nrf" --scene demo
expect_exit 0 "$NERAF" export --run "$M" --out "$TMP/dead.nrf" --scene 1
cmp -s "$TMP/demo.nrf" "$TMP/dead.nrf" && fail "the two scenes' exports are identical"
expect_exit 0 "$NERAF" render rir --run "$M" --scene small_dead --mic 1.5,1.2,1.3 \
  --src 1.0,1.2,1.0 --yaw 90 --out "$TMP/before.wav" --allow-outside
expect_exit 1 "$NERAF" render rir --run "$VA" --scene demo --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --yaw 90 --out "$TMP/x.wav"
expect_exit 0 "$NERAF" eval --model "$TMP/dead.nrf" --json "$TMP/model.json" --max-rirs 2 \
  --no-baselines --quiet
# The small room renders its own length, through the run and through its export alike.
expect_exit 0 "$NERAF" render rir --model "$TMP/dead.nrf" --mic 1.5,1.2,1.3 --src 1.0,1.2,1.0 \
  --yaw 90 --out "$TMP/dead_model.wav" --allow-outside
expect_exit 0 "$NERAF" render rir --run "$M" --scene demo --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --yaw 90 --out "$TMP/demo_run.wav"
[ "$(stat -c %s "$TMP/dead_model.wav")" = "$(stat -c %s "$TMP/before.wav")" ] ||
  fail "the exported small room renders another length than its run"
[ "$(stat -c %s "$TMP/before.wav")" -lt "$(stat -c %s "$TMP/demo_run.wav")" ] ||
  fail "the small room is not rendered at its own (shorter) length"

# --- eval: every scene and the mean, with a --grid zeros ablation trained alike -----------------
expect_exit 0 "$NERAF" train --data "$A" --vision-run "$VA" --data "$B" --vision-run "$VB" \
  --out "$TMP/zeros" --grid zeros "${common[@]}"
expect_exit 0 "$NERAF" eval --run "$M" --json "$TMP/eval.json" --max-rirs 3 --no-images \
  --ablation-runs "$TMP/zeros" --quiet
for key in '"scenes"' '"mean"' '"demo"' '"small_dead"' '"scene_order"' '"paired_ablations"' \
  '"zeros"' '"t60_error_pct"'; do
  expect_in "$TMP/eval.json" "$key"
done
expect_in "$TMP/out" "mean over 2 scenes"
expect_file "$M/eval/demo/audio_per_rir.csv"
expect_file "$M/eval/small_dead/audio_per_rir.csv"
# Each scene's mean is its own: the two scenes' neraf T60 errors differ.
python3 - "$TMP/eval.json" <<'EOF' || fail "eval.json: per-scene and mean metrics inconsistent"
import json, sys
a = json.load(open(sys.argv[1]))["audio"]
s = [a["scenes"][n]["neraf"]["t60_error_pct"] for n in a["scene_order"]]
assert len(s) == 2 and s[0] != s[1], s
assert abs(a["mean"]["neraf"]["t60_error_pct"] - sum(s) / 2) < 1e-9, a["mean"]["neraf"]
assert a["mean"]["neraf"]["n_rirs"] == 6
EOF
expect_exit 1 "$NERAF" eval --run "$M" --json "$TMP/x.json" --data "$A" --quiet
expect_in "$TMP/err" "multi-scene run records each scene's dataset"
# A one-scene ablation of a multi-scene run is refused (it was not trained alike).
expect_exit 0 "$NERAF" train --data "$A" --vision-run "$VA" --out "$TMP/one" "${common[@]}"
expect_exit 1 "$NERAF" eval --run "$M" --json "$TMP/x.json" --max-rirs 1 --ablation-runs \
  "$TMP/one" --quiet

# --- resume: killed after step 3, continued to 5, the same RIR as without the interruption ------
rm -f "$M"/checkpoints/step-000000005.*
expect_exit 0 "$NERAF" train --out "$M" --resume --quiet
expect_file "$M/checkpoints/step-000000005.pt"
expect_exit 0 "$NERAF" render rir --run "$M" --scene small_dead --mic 1.5,1.2,1.3 \
  --src 1.0,1.2,1.0 --yaw 90 --out "$TMP/after.wav" --allow-outside
cmp -s "$TMP/before.wav" "$TMP/after.wav" || fail "the resumed multi-scene run differs"

# --- bad input: one clear line each, nothing left behind ----------------------------------------
expect_exit 1 "$NERAF" train --data "$A" --vision-run "$VA" --data "$B" --out "$TMP/bad" \
  "${common[@]}"
expect_in "$TMP/err" "one --vision-run per --data"
expect_exit 1 "$NERAF" train --data "$A" --vision-run "$VA" --vision-run "$VB" --out "$TMP/bad" \
  "${common[@]}"
expect_in "$TMP/err" "one --vision-run per --data"
# Vision runs swapped: each scene's grid must come from its own room.
expect_exit 1 "$NERAF" train --data "$A" --vision-run "$VB" --data "$B" --vision-run "$VA" \
  --out "$TMP/bad" "${common[@]}"
expect_in "$TMP/err" "pass the vision run trained on this dataset"
# The demo room in the RAF layout (48 kHz mono), with its own vision run.
expect_exit 0 "$NERAF" synth --preset demo --layout raf --out "$TMP/demo_raf" --seed 3 --quiet
expect_exit 0 "$NERAF" train --data "$TMP/demo_raf" --modality vision --steps 1 --rays 128 \
  --out "$TMP/v-raf" --quiet
expect_exit 1 "$NERAF" train --data "$A" --vision-run "$VA" --data "$TMP/demo_raf" \
  --vision-run "$TMP/v-raf" --out "$TMP/bad" "${common[@]}"
expect_in "$TMP/err" "one multi-scene run needs scenes of one layout, sample rate and STFT"
expect_exit 1 "$NERAF" train --data "$A" --data "$B" --modality joint --out "$TMP/bad" --quiet
expect_in "$TMP/err" "--modality audio only"
[ -e "$TMP/bad" ] && fail "a refused run left $TMP/bad behind"
for f in "$TMP/err"; do [ "$(wc -l <"$f")" -le 1 ] || fail "more than one error line: $(cat "$f")"; done

finish multiscene
