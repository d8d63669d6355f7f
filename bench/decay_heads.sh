#!/usr/bin/env bash
# Does NAcF with decay heads (`neraf train --decay-heads`: a slope per bin beside each level head,
# out = tanh(level + τ·slope)) predict reverberant tails better than the published heads?
# Per room (the demo room in the SoundSpaces layout, the occluded room, RAF's furnished room):
#   1. `neraf synth` the room (seed 1) and the same room at 40 random new microphone positions
#      (seed 2, --gain-from), as scripts/experiments.sh does;
#   2. one vision run (the cpu preset's 2000 steps, seed 1) whose frozen field fills the grid;
#   3. per seed: two audio runs of AUDIO_STEPS steps on it, identical but for --decay-heads;
#   4. `neraf eval --run DECAY --ablation-runs BASE --novel-data`: the decay-head run against
#      nearest / linear interpolation and, paired per RIR, against the published heads, on the
#      held-out split and at the new positions;
#   5. in the rooms ZEROS_ROOMS names (default: the occluded room, issue 13's target room), the
#      paper's zero-grid ablation of the decay-head run: one more run per seed with
#      --decay-heads --grid zeros, scored against it the same way.
# Then bench/decay_heads_summary.py gathers the evaluations into RESULT: per room and split the
# mean over seeds of the paired difference decay − published (± standard error over seeds).
# TRAIN_ARGS (e.g. "--grid-features local") go to every audio run, so the comparisons above hold
# with that option on both sides.
# Quality only (not timing): seeds run PARALLEL at a time with THREADS threads each.
# Usage: bench/decay_heads.sh   (env: NERAF, WORK, RESULT, SEEDS, AUDIO_STEPS, THREADS, PARALLEL,
# ROOMS, ZEROS_ROOMS, TRAIN_ARGS)
set -euo pipefail
cd "$(dirname "$0")/.."
NERAF=${NERAF:-build/neraf}
WORK=${WORK:-build/decay_heads}
RESULT=${RESULT:-$WORK/decay_heads.json}
SEEDS=${SEEDS:-1 2 3}
AUDIO_STEPS=${AUDIO_STEPS:-1500}
THREADS=${THREADS:-1}
PARALLEL=${PARALLEL:-2}
ROOMS=${ROOMS:-ss_demo occluded raf_furnished}
ZEROS_ROOMS=${ZEROS_ROOMS-occluded}
read -r -a TRAIN_ARGS <<<"${TRAIN_ARGS:-}"
mkdir -p "$WORK"
LOAD_BEFORE=$(cut -d' ' -f1-3 /proc/loadavg)
START=$(date -u +%FT%TZ)
T0=$SECONDS
log() { echo "[$(date -u +%T)] $*"; }

synth_args() {
  case $1 in
    ss_demo) echo --preset demo --layout soundspaces ;;
    occluded) echo --preset occluded ;;
    raf_furnished) echo --preset furnished_room ;;
    *) echo "decay_heads.sh: unknown room '$1' (use ss_demo, occluded, raf_furnished)" >&2; exit 2 ;;
  esac
}

# seed_runs ROOM SEED: both audio runs of one seed and their evaluation
seed_runs() {
  local r=$1 s=$2 base=$WORK/$1/base_s$2 decay=$WORK/$1/decay_s$2
  local a=(train --modality audio --data "$WORK/$r/data" --vision-run "$WORK/$r/vision" --seed "$s"
    --steps "$AUDIO_STEPS" --threads "$THREADS" --force --quiet "${TRAIN_ARGS[@]}")
  [ -f "$base/done" ] || { "$NERAF" "${a[@]}" --out "$base" && touch "$base/done"; }
  [ -f "$decay/done" ] || { "$NERAF" "${a[@]}" --decay-heads --out "$decay" && touch "$decay/done"; }
  # neraf writes the JSON atomically: it exists only once the evaluation is complete.
  [ -f "$WORK/$r/eval_s$s.json" ] || "$NERAF" eval --run "$decay" --ablation-runs "$base" \
    --novel-data "$WORK/$r/novel" --skip-vision --no-images --threads "$THREADS" \
    --json "$WORK/$r/eval_s$s.json" --quiet >/dev/null
  case " $ZEROS_ROOMS " in
    *" $r "*)
      local zeros=$WORK/$r/zeros_s$s
      [ -f "$zeros/done" ] ||
        { "$NERAF" "${a[@]}" --decay-heads --grid zeros --out "$zeros" && touch "$zeros/done"; }
      [ -f "$WORK/$r/eval_zeros_s$s.json" ] || "$NERAF" eval --run "$decay" --ablation-runs "$zeros" \
        --novel-data "$WORK/$r/novel" --skip-vision --no-images --threads "$THREADS" \
        --json "$WORK/$r/eval_zeros_s$s.json" --quiet >/dev/null
      ;;
  esac
  log "$r seed $s done"
}

for r in $ROOMS; do
  read -r -a synth <<<"$(synth_args "$r")"
  [ -f "$WORK/$r/data/synth_info.json" ] ||
    "$NERAF" synth "${synth[@]}" --seed 1 --out "$WORK/$r/data" --force --quiet
  [ -f "$WORK/$r/novel/synth_info.json" ] ||
    "$NERAF" synth "${synth[@]}" --mics random --mic-count 40 --seed 2 --gain-from "$WORK/$r/data" \
      --out "$WORK/$r/novel" --force --quiet
  if [ ! -f "$WORK/$r/vision/done" ]; then
    log "$r: vision run"
    "$NERAF" train --data "$WORK/$r/data" --modality vision --seed 1 --out "$WORK/$r/vision" \
      --force --quiet
    touch "$WORK/$r/vision/done"
  fi
  running=0
  for s in $SEEDS; do
    seed_runs "$r" "$s" &
    running=$((running + 1))
    if [ "$running" -ge "$PARALLEL" ]; then wait -n; running=$((running - 1)); fi
  done
  wait
done

CPU=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | xargs)
/usr/bin/python3 bench/decay_heads_summary.py --work "$WORK" --rooms $ROOMS --seeds $SEEDS \
  --zeros-rooms $ZEROS_ROOMS --machine "$CPU" \
  --command "bench/decay_heads.sh (SEEDS=\"$SEEDS\" AUDIO_STEPS=$AUDIO_STEPS THREADS=$THREADS PARALLEL=$PARALLEL TRAIN_ARGS=\"${TRAIN_ARGS[*]}\")" \
  --start "$START" --load-before "$LOAD_BEFORE" --seconds $((SECONDS - T0)) --out "$RESULT"
