#!/usr/bin/env bash
# The README's main command: the whole neraf story on the built-in demo scene.
#   synthesize -> train jointly -> evaluate -> render a RIR, an auralized WAV, a view, a loudness map
# Installs the Debian packages, builds, then writes everything into demo-out/ (or $NERAF_DEMO_OUT).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh --target neraf
NERAF=build/neraf
OUT=${NERAF_DEMO_OUT:-demo-out}
mkdir -p "$OUT"

# Poses in the dataset's frame as NeRAF reads it (metres, y up); see `neraf render rir --help`.
MIC=2.0,1.5,2.5
SRC=1.1,1.2,0.9

step() { printf '\n== %s\n' "$*"; }

step "1/7 synthesize the demo room (pictures + binaural RIRs, SoundSpaces layout)"
$NERAF synth --preset demo --layout soundspaces --out "$OUT/scene" --seed 1 --force
$NERAF info "$OUT/scene"
# The same room heard at 50 random microphone positions the training never sees (its test split
# holds out source/heading pairs at trained positions), at the same scale: scored by eval
# --novel-data.
$NERAF synth --preset demo --layout soundspaces --mics random --out "$OUT/novel" --seed 2 \
  --gain-from "$OUT/scene" --force --quiet

step "2/7 train the radiance and acoustic fields jointly (cpu preset), then the ablations"
$NERAF train --data "$OUT/scene" --out "$OUT/run" --force
# Ablations compared fairly: the full model and each ablation train alike (eval refuses any other
# difference), here the acoustic field alone on the joint run's frozen field, 2000 steps each (as
# many audio steps as the joint run): the full model, the paper's no-grid and all-zero-grid, and
# without the relative-geometry inputs (absolute positions only, as the reference's NAcF gets
# them).
AUDIO=(train --data "$OUT/scene" --modality audio --vision-run "$OUT/run" --steps 2000 --force)
$NERAF "${AUDIO[@]}" --out "$OUT/run_audio"
for grid in none zeros; do
  $NERAF "${AUDIO[@]}" --grid $grid --out "$OUT/ablation_grid_$grid"
done
$NERAF "${AUDIO[@]}" --no-relative-geometry --out "$OUT/ablation_absolute_positions"

step "3/7 evaluate on the held-out RIRs, new microphone positions and views (baselines alongside), then the ablations against the audio-only full model"
$NERAF eval --run "$OUT/run" --json "$OUT/eval.json" --novel-data "$OUT/novel"
$NERAF eval --run "$OUT/run_audio" --json "$OUT/eval_ablations.json" --novel-data "$OUT/novel" \
  --skip-vision --no-baselines \
  --ablation-runs "$OUT/ablation_grid_none,$OUT/ablation_grid_zeros,$OUT/ablation_absolute_positions"

step "4/7 render a RIR at a new pose and auralize speech with it"
$NERAF render rir --run "$OUT/run" --mic "$MIC" --src "$SRC" --yaw 90 --out "$OUT/rir.wav"
$NERAF metrics --rir "$OUT/rir.wav"
espeak-ng -w "$OUT/dry_speech.wav" "This is how the demo room sounds, rendered by neraf."
$NERAF auralize --run "$OUT/run" --mic "$MIC" --src "$SRC" --yaw 90 \
  --in "$OUT/dry_speech.wav" --out "$OUT/speech_in_room.wav" --normalize

step "5/7 render a held-out view"
$NERAF render view --run "$OUT/run" --frame 0 --out "$OUT/view.png" --depth "$OUT/depth.png"

step "6/7 draw the loudness map of the source"
$NERAF render loudness --run "$OUT/run" --src "$SRC" --yaw 90 --out "$OUT/loudness.png"

step "7/7 export the acoustic field for the runtime (neraf_rt) and walk a listener through the room"
$NERAF export --run "$OUT/run" --out "$OUT/demo.nrf"
$NERAF render trajectory --model "$OUT/demo.nrf" --path examples/paths/demo_walk.json \
  --in "$OUT/dry_speech.wav" --out "$OUT/speech_walk.wav" --normalize
rm -rf "$OUT/rirs"
$NERAF render rir --model "$OUT/demo.nrf" --poses examples/paths/demo_poses.json --out "$OUT/rirs"

printf '\nDemo outputs in %s/: eval.json, eval_ablations.json, rir.wav, speech_in_room.wav, view.png,\n' "$OUT"
printf 'loudness.png, demo.nrf (the exported acoustic field), speech_walk.wav (a walk through the\n'
printf 'room), rirs/\n'
