#!/usr/bin/env bash
# The whole story through the `neraf` program on a tiny run: synth → train (joint, a few steps)
# → resume → eval → render rir / view / loudness → auralize, plus the bad inputs a user meets on
# the way (one-line errors, exit codes, warnings). Not a quality check: a few steps only.
# Usage: cli_pipeline.sh <path to neraf> <assets dir>
set -u
NERAF=$1
ASSETS=$2
source "$(dirname "$0")/lib.sh"

S=$TMP/scene R=$TMP/run
MIC=2.0,1.5,2.5 SRC=1.1,1.2,0.9

expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --out "$S" --seed 3
expect_exit 0 "$NERAF" info "$S"
expect_in "$TMP/out" "0 error(s)"

# --- train: joint, audio from step 3; then resume to step 8 -----------------------------------
expect_exit 0 "$NERAF" train --data "$S" --out "$R" --steps 5 --audio-start-step 3 --rays 256 --quiet
expect_file "$R/config.json"
expect_file "$R/checkpoints/step-000000005.pt"
expect_exit 1 "$NERAF" train --data "$S" --out "$R" --steps 5
expect_in "$TMP/err" "--resume"
expect_exit 1 "$NERAF" train --out "$R" --resume --grid zeros
expect_in "$TMP/err" "cannot change on --resume"
expect_exit 0 "$NERAF" train --out "$R" --resume --steps 8 --quiet
expect_file "$R/checkpoints/step-000000008.pt"
expect_exit 2 "$NERAF" train --data "$S" --out "$TMP/r2" --modality sound

# --- eval -------------------------------------------------------------------------------------
expect_exit 0 "$NERAF" eval --run "$R" --json "$TMP/eval.json" --max-views 2 --max-rirs 4 --quiet
# The calibrated run scored with and without its calibration, each row naming its post-processing.
for key in '"neraf"' '"neraf_uncalibrated"' '"nearest"' '"linear"' '"t60_error_pct"' '"psnr"' \
  '"paired_uncalibrated"' '"post_processing": "griffin_lim_calibrated"'; do
  expect_in "$TMP/eval.json" "$key"
done
expect_in "$TMP/out" "neraf_uncalibrated"
expect_file "$R/eval/audio_per_rir.csv"
# New microphone positions in the same room, and an ablation compared fairly: the full model and
# the ablation with absolute positions only, both audio-only on the joint run's frozen field with
# the same steps and seed.
expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --mics random --mic-count 2 \
  --out "$TMP/novel" --seed 4 --gain-from "$S" --quiet
expect_exit 0 "$NERAF" train --data "$S" --modality audio --vision-run "$R" --steps 2 \
  --out "$TMP/full" --quiet
expect_exit 0 "$NERAF" train --data "$S" --modality audio --vision-run "$R" --steps 2 \
  --no-relative-geometry --out "$TMP/absolute" --quiet
expect_exit 0 "$NERAF" eval --run "$TMP/full" --json "$TMP/novel.json" --skip-vision --max-rirs 3 \
  --novel-data "$TMP/novel" --ablation-runs "$TMP/absolute" --quiet
for key in '"novel"' '"absolute"' '"relative_geometry": false' '"paired_ablations"'; do
  expect_in "$TMP/novel.json" "$key"
done
expect_in "$TMP/out" "new microphone positions"
expect_file "$TMP/full/eval/audio_novel_per_rir.csv"
# An ablation trained unlike the run it is compared with is refused, naming the run and the
# setting: audio-only against the joint run, another step count, another seed; and with --model.
expect_exit 1 "$NERAF" eval --run "$R" --json "$TMP/x.json" --skip-vision --max-rirs 1 \
  --ablation-runs "$TMP/absolute" --quiet
expect_in "$TMP/err" "absolute was not trained like --run"
expect_in "$TMP/err" 'config.json modality: "audio" vs "joint"'
[ ! -e "$TMP/x.json" ] || fail "a refused --ablation-runs wrote $TMP/x.json"
expect_exit 0 "$NERAF" train --data "$S" --modality audio --vision-run "$R" --steps 3 \
  --no-relative-geometry --out "$TMP/absolute3" --quiet
expect_exit 1 "$NERAF" eval --run "$TMP/full" --json "$TMP/x.json" --skip-vision --max-rirs 1 \
  --ablation-runs "$TMP/absolute3" --quiet
expect_in "$TMP/err" "absolute3 was not trained like --run"
expect_in "$TMP/err" "config.json steps: 3 vs 2"
expect_exit 0 "$NERAF" train --data "$S" --modality audio --vision-run "$R" --steps 2 --seed 5 \
  --no-relative-geometry --out "$TMP/absolute_seed5" --quiet
expect_exit 1 "$NERAF" eval --run "$TMP/full" --json "$TMP/x.json" --skip-vision --max-rirs 1 \
  --ablation-runs "$TMP/absolute,$TMP/absolute_seed5" --quiet
expect_in "$TMP/err" "config.json seed: 5 vs 42"
# The same positions at the automatic gain: another scale, refused (it would bias the STFT error).
expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --mics random --mic-count 2 \
  --out "$TMP/novel_scaled" --seed 4 --quiet
expect_exit 1 "$NERAF" eval --run "$R" --json "$TMP/x.json" --skip-vision \
  --novel-data "$TMP/novel_scaled"
expect_in "$TMP/err" "--gain-from"
expect_exit 2 "$NERAF" synth --preset demo --gain-from "$TMP/no-such-set" --out "$TMP/x" --quiet
expect_exit 0 "$NERAF" synth --preset demo --layout raf --out "$TMP/raf" --seed 4 --quiet
expect_exit 1 "$NERAF" eval --run "$R" --json "$TMP/x.json" --skip-vision --novel-data "$TMP/raf"
expect_in "$TMP/err" "is not a soundspaces dataset as the run's is"
[ ! -e "$TMP/raf/.neraf_cache" ] || fail "a refused --novel-data was left a feature cache"
# Another room is not new positions of the run's room: synth will not give it the run's gain,
# and eval refuses it whatever its gain.
expect_exit 1 "$NERAF" synth --preset small_dead --layout soundspaces --mics random --mic-count 2 \
  --out "$TMP/other_room" --seed 4 --gain-from "$S" --quiet
expect_in "$TMP/err" "is another room than preset small_dead"
expect_exit 0 "$NERAF" synth --preset small_dead --layout soundspaces --mics random --mic-count 2 \
  --out "$TMP/other_room" --seed 4 --quiet
expect_exit 1 "$NERAF" eval --run "$R" --json "$TMP/x.json" --skip-vision \
  --novel-data "$TMP/other_room"
expect_in "$TMP/err" "is another room than the run's data"
expect_exit 1 "$NERAF" synth --preset demo --mic-count 3 --out "$TMP/x" --quiet
expect_in "$TMP/err" "--mics random"
expect_exit 1 "$NERAF" eval --run "$TMP/no-such-run" --json "$TMP/x.json"
expect_in "$TMP/err" "no-such-run"

# --- render -----------------------------------------------------------------------------------
expect_exit 0 "$NERAF" render rir --run "$R" --mic "$MIC" --src "$SRC" --yaw 90 --out "$TMP/rir.wav"
expect_exit 0 "$NERAF" metrics --rir "$TMP/rir.wav" --json
expect_in "$TMP/out" '"channels"'
expect_exit 2 "$NERAF" render rir --run "$R" --mic "$MIC" --src "$SRC" --yaw north --out "$TMP/x.wav"
expect_exit 2 "$NERAF" render rir --run "$R" --mic 2.0,1.5 --src "$SRC" --out "$TMP/x.wav"
expect_in "$TMP/err" "--mic"
expect_exit 1 "$NERAF" render rir --run "$R" --mic 40,1.5,2.5 --src "$SRC" --out "$TMP/far.wav"
expect_in "$TMP/err" "--allow-outside"
expect_exit 0 "$NERAF" render rir --run "$R" --mic 40,1.5,2.5 --src "$SRC" --out "$TMP/far.wav" --allow-outside
expect_in "$TMP/err" "outside"
expect_exit 0 "$NERAF" render view --run "$R" --frame 0 --out "$TMP/view.png" --depth "$TMP/depth.png"
expect_file "$TMP/view.png"
expect_file "$TMP/depth.png"
expect_exit 1 "$NERAF" render view --run "$R" --frame 9999 --out "$TMP/x.png"
expect_exit 0 "$NERAF" render loudness --run "$R" --src "$SRC" --spacing 0.5 --out "$TMP/map.png"
expect_file "$TMP/map.png"
expect_file "$TMP/map.csv"

# --- auralize with the rendered field ---------------------------------------------------------
expect_exit 0 "$NERAF" auralize --run "$R" --mic "$MIC" --src "$SRC" --yaw 90 \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/wet.wav" --normalize
expect_exit 0 "$NERAF" metrics --rir "$TMP/wet.wav"

# --- export → the runtime (neraf_rt) gives the run's numbers -----------------------------------
EX=$(cd "$(dirname "$0")/../../examples/paths" && pwd)
M=$TMP/m.nrf
expect_exit 0 "$NERAF" export --run "$R" --out "$M"
expect_in "$TMP/out" "runtime vs LibTorch"
expect_exit 0 "$NERAF" export --run "$R" --out "$TMP/m16.nrf" --precision bf16
[ "$(stat -c %s "$TMP/m16.nrf")" -lt "$(stat -c %s "$M")" ] || fail "bf16 export is not smaller"
expect_exit 0 "$NERAF" eval --run "$R" --json "$TMP/e_run.json" --skip-vision --max-rirs 4 --no-images --quiet
expect_exit 0 "$NERAF" eval --model "$M" --json "$TMP/e_model.json" --max-rirs 4 --no-images --quiet
expect_exit 0 "$NERAF" eval --run "$R" --json "$TMP/e_bf16.json" --skip-vision --max-rirs 2 --no-images --quiet --precision bf16
expect_in "$TMP/e_bf16.json" '"precision": "bf16"'
expect_exit 2 "$NERAF" render rir --model "$M" --mic "$MIC" --src "$SRC" --precision bf16 --out "$TMP/x.wav"
python3 - "$TMP/e_run.json" "$TMP/e_model.json" <<'PY' || fail "eval --model differs from eval --run"
import json, sys
a, b = (json.load(open(p))["audio"] for p in sys.argv[1:])
for method in ("neraf", "nearest", "linear"):
    for key in ("t60_error_pct", "c50_error_db", "edt_error_s", "stft_error"):
        x, y = a[method][key], b[method][key]
        assert abs(x - y) <= 1e-3 * (1 + abs(x)), (method, key, x, y)
PY
expect_exit 0 "$NERAF" render rir --model "$M" --mic "$MIC" --src "$SRC" --yaw 90 --out "$TMP/rir_m.wav"
expect_exit 0 "$NERAF" render loudness --model "$M" --src "$SRC" --spacing 0.5 --out "$TMP/map_m.png"
expect_exit 0 "$NERAF" auralize --model "$M" --mic "$MIC" --src "$SRC" --yaw 90 \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/wet_m.wav"
expect_exit 1 "$NERAF" render rir --model "$M" --mic 40,1.5,2.5 --src "$SRC" --out "$TMP/x.wav"
expect_in "$TMP/err" "--allow-outside"
head -c 1000 "$M" >"$TMP/cut.nrf"
expect_exit 1 "$NERAF" render rir --model "$TMP/cut.nrf" --mic "$MIC" --src "$SRC" --out "$TMP/x.wav"
expect_in "$TMP/err" "cut.nrf"
[ ! -e "$TMP/x.wav" ] || fail "a failed render left $TMP/x.wav"
expect_exit 2 "$NERAF" render rir --run "$R" --model "$M" --mic "$MIC" --src "$SRC" --out "$TMP/x.wav"

# --- many poses, trajectories ------------------------------------------------------------------
expect_exit 0 "$NERAF" render rir --model "$M" --poses "$EX/demo_poses.json" --out "$TMP/rirs/"
expect_file "$TMP/rirs/summary.csv"
expect_file "$TMP/rirs/near_source.wav"
expect_file "$TMP/rirs/pose_0005.wav"
[ "$(wc -l <"$TMP/rirs/summary.csv")" -eq 8 ] || fail "summary.csv: expected a header and 7 rows"
expect_exit 1 "$NERAF" render rir --model "$M" --poses "$EX/demo_poses.json" --out "$TMP/rirs"
expect_in "$TMP/err" "not an empty folder"
printf '{"version":1,"source":[1,1,1],"poses":[{"mic":[1,NaN,1]}]}' >"$TMP/nan.json"
expect_exit 1 "$NERAF" render rir --model "$M" --poses "$TMP/nan.json" --out "$TMP/rirs_nan"
[ ! -e "$TMP/rirs_nan" ] || fail "a failed --poses left a folder"
expect_exit 0 "$NERAF" render trajectory --model "$M" --path "$EX/demo_walk.json" \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/walk.wav" --rate 10
expect_in "$TMP/out" "RIRs from"
expect_exit 0 "$NERAF" metrics --rir "$TMP/walk.wav"
expect_exit 0 "$NERAF" render trajectory --run "$R" --path "$EX/demo_walk.json" \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/walk_run.wav" --rate 2 --frames "$TMP/frames" --fps 0.5
expect_file "$TMP/frames/frame_00000.png"
printf '{"version":1,"source":[1.1,1.2,0.9],"keyframes":[{"time":1,"mic":[2,1.5,2],"yaw":0},{"time":0.5,"mic":[2,1.5,2],"yaw":0}]}' >"$TMP/back.json"
expect_exit 1 "$NERAF" render trajectory --model "$M" --path "$TMP/back.json" \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/x.wav"
expect_in "$TMP/err" "back.json"
printf '{"version":1,"source":[1.1,1.2,0.9],"keyframes":[{"time":0,"mic":[40,1.5,2],"yaw":0}]}' >"$TMP/far.json"
expect_exit 1 "$NERAF" render trajectory --model "$M" --path "$TMP/far.json" \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/x.wav"
expect_in "$TMP/err" "--allow-outside"
expect_exit 2 "$NERAF" render trajectory --model "$M" --path "$EX/demo_walk.json" \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/x.wav" --block 0
expect_exit 1 "$NERAF" render trajectory --model "$M" --path "$EX/demo_walk.json" \
  --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/x.wav" --frames "$TMP/f2"
expect_in "$TMP/err" "--frames"

# --- a vision-only run has no acoustic field --------------------------------------------------
expect_exit 0 "$NERAF" train --data "$S" --modality vision --out "$TMP/vis" --steps 2 --rays 256 --quiet
expect_exit 1 "$NERAF" render rir --run "$TMP/vis" --mic "$MIC" --src "$SRC" --out "$TMP/x.wav"
expect_in "$TMP/err" "vision"

finish "CLI pipeline"
