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
for key in '"neraf"' '"nearest"' '"linear"' '"t60_error_pct"' '"psnr"'; do
  expect_in "$TMP/eval.json" "$key"
done
expect_file "$R/eval/audio_per_rir.csv"
# New microphone positions in the same room, and an ablation run with absolute positions only.
expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --mics random --mic-count 2 \
  --out "$TMP/novel" --seed 4 --gain-from "$S" --quiet
expect_exit 0 "$NERAF" train --data "$S" --modality audio --vision-run "$R" --steps 2 \
  --no-relative-geometry --out "$TMP/absolute" --quiet
expect_exit 0 "$NERAF" eval --run "$R" --json "$TMP/novel.json" --skip-vision --max-rirs 3 \
  --novel-data "$TMP/novel" --ablation-runs "$TMP/absolute" --quiet
for key in '"novel"' '"absolute"' '"relative_geometry": false'; do
  expect_in "$TMP/novel.json" "$key"
done
expect_in "$TMP/out" "new microphone positions"
expect_file "$R/eval/audio_novel_per_rir.csv"
# The same positions at the automatic gain: another scale, refused (it would bias the STFT error).
expect_exit 0 "$NERAF" synth --preset demo --layout soundspaces --mics random --mic-count 2 \
  --out "$TMP/novel_scaled" --seed 4 --quiet
expect_exit 1 "$NERAF" eval --run "$R" --json "$TMP/x.json" --skip-vision \
  --novel-data "$TMP/novel_scaled"
expect_in "$TMP/err" "--gain-from"
expect_exit 2 "$NERAF" synth --preset demo --gain-from "$TMP/no-such-set" --out "$TMP/x" --quiet
expect_exit 0 "$NERAF" synth --preset demo --layout raf --out "$TMP/raf" --seed 4 --quiet
expect_exit 1 "$NERAF" eval --run "$R" --json "$TMP/x.json" --skip-vision --novel-data "$TMP/raf"
expect_in "$TMP/err" "differs from the run's"
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
expect_exit 0 "$NERAF" render rir --run "$R" --mic 40,1.5,2.5 --src "$SRC" --out "$TMP/far.wav"
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

# --- a vision-only run has no acoustic field --------------------------------------------------
expect_exit 0 "$NERAF" train --data "$S" --modality vision --out "$TMP/vis" --steps 2 --rays 256 --quiet
expect_exit 1 "$NERAF" render rir --run "$TMP/vis" --mic "$MIC" --src "$SRC" --out "$TMP/x.wav"
expect_in "$TMP/err" "vision"

finish "CLI pipeline"
