#!/usr/bin/env bash
# The NeRAF paper's experiments, reproduced on simulated rooms with the cpu preset (issue 13):
#   1. neraf vs nearest / linear interpolation: a SoundSpaces-layout binaural room and a
#      RAF-layout mono room with directional sources; held-out split and new microphone positions;
#      and the grid read per query (--grid-features local and both) beside the global feature
#   2. the grid ablation (no grid, zero grid, S = 24 / 32 / 64) on the occluded room and on the
#      furnished / empty pair (S = 16 cannot pass the scene encoder, which halves the grid four
#      times: BatchNorm would see one voxel), and the grid read per query (--grid-features local
#      and both) beside the published global feature
#   3. few-shot: 25 / 50 / 75 / 100 % of the training RIRs, baselines given the same RIRs, and
#      the grid read per query beside the global feature at the fractions below 100 %
#   4. cross-modal vision: vision-only vs joint with 10 / 20 / 40 training views
#   5. the loss study: SC+SL-MSE vs SC+SL-L1 vs MSE
# Every run is repeated over SEEDS; every comparison is paired per RIR (neraf eval) and then
# summarised over seeds by scripts/experiments_report.py, which writes docs/RESULTS.md, its plots
# (docs/images/results/) and copies every eval JSON it read to docs/results/experiments/.
#
#   scripts/experiments.sh            the full run (not part of CI; see docs/RESULTS.md for its
#                                     time on 2 cores)
#   scripts/experiments.sh --quick    a smoke run with tiny schedules into build/experiments-quick
#                                     (checks the script end to end in minutes; its numbers mean
#                                     nothing)
#   EXPERIMENTS="1 3" scripts/...     only these experiments (the report covers what exists)
#   E1_ROOMS="raf_furnished" ...      experiment 1 on these of its rooms only (default: both,
#                                     ss_demo raf_furnished)
#   E1_FEATURES=0 scripts/...         experiment 1 without its per-query variants (--grid-features
#                                     local and both: two more joint runs per room and seed)
#   E2_ROOMS="occluded" scripts/...   experiment 2 on these of its rooms only (default: all three,
#                                     occluded raf_furnished raf_empty)
#   E3_FEATURES="0.25" scripts/...    experiment 3's per-query variants at these fractions only
#                                     (default: 0.25 0.5 0.75; "" for none)
#   E4_VIEWS="10" scripts/...         experiment 4 with these training-view counts only (default:
#                                     10 20 40)
#   JOBS=2 scripts/...                two runs at once with half the cores' threads each, instead of
#                                     one with all of them: 1.3x the runs per hour on 2 cores
#                                     (bench/experiments_jobs.sh); the numbers differ from a JOBS=1 call's
#                                     (another --threads), so let one table come from one JOBS.
#                                     The vision runs that several runs share train alone, with
#                                     all cores, whatever JOBS is
#   PROVENANCE=FILE scripts/...       the report's header lists the calls in FILE (Markdown)
#                                     instead of naming this call alone: for results gathered over
#                                     several partial calls (docs/results/experiments_provenance.md;
#                                     add this call to it first)
# Runs are kept in build/experiments/: a finished run is not trained again, and an eval JSON is
# kept while it is newer than every run it scores, so an interrupted call continues where it
# stopped (an unfinished training resumes from its last checkpoint) and a run trained again is
# scored again.
set -euo pipefail
cd "$(dirname "$0")/.."
QUICK=0
[ "${1:-}" = "--quick" ] && QUICK=1
JOBS=${JOBS:-1}
case $JOBS in
  '' | *[!0-9]* | 0)
    echo "experiments: JOBS takes a whole number from 1 to the cores ($(nproc)), not '$JOBS'" >&2
    exit 2
    ;;
esac
if [ "$JOBS" -gt "$(nproc)" ]; then
  echo "experiments: JOBS=$JOBS is more than the $(nproc) cores; use JOBS=$(nproc) or fewer" >&2
  exit 2
fi
scripts/setup.sh
if ! /usr/bin/python3 -c 'import matplotlib' 2>/dev/null; then  # plots only; not a build dependency
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends python3-matplotlib
fi
scripts/build.sh --target neraf
EXPERIMENTS=${EXPERIMENTS:-"1 2 3 4 5"}

if [ "$QUICK" = 1 ]; then
  OUT=build/experiments-quick
  REPORT=(--doc "$OUT/RESULTS.md" --raw "$OUT/results" --images "$OUT/images")
  SEEDS=(1 2)
  JOINT=(--steps 40 --audio-start-step 20 --rays 256)
  VISION=(--steps 30 --rays 256)
  AUDIO=(--steps 30)
  VIEWS_JOINT=(--steps 40 --audio-start-step 20 --rays 256)
  VIEWS_VISION=(--steps 40 --rays 256)
  MICS=(--mics random --mic-count 12)
else
  OUT=build/experiments
  REPORT=(--doc docs/RESULTS.md --raw docs/results/experiments --images docs/images/results)
  SEEDS=(1 2 3)
  # The cpu preset's fixed schedule, given explicitly: without --steps a larger room would get more
  # audio steps (fit_run_length_to_data), and a few-shot run fewer than the full one.
  JOINT=(--steps 3000)  # cpu preset, joint, 3000 steps (audio from step 1000)
  VISION=()             # cpu vision run: 2000 steps
  AUDIO=(--steps 1500)  # cpu audio run on a frozen field: 1500 steps
  # Experiment 4 compares vision-only with joint training at the same number of steps (joint's
  # 3000), so the only difference is the acoustic branch.
  VIEWS_JOINT=()
  VIEWS_VISION=(--steps 3000)
  MICS=()
fi
mkdir -p "$OUT"
LOG=$OUT/experiments.log
# The runs use a copy of the binary: a run started while build/neraf is being relinked would fail.
NERAF=$PWD/$OUT/neraf
cp build/neraf "$NERAF.tmp" && mv "$NERAF.tmp" "$NERAF"
echo "experiments: $(date -u +%FT%TZ) on $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)," \
  "experiments: $EXPERIMENTS, seeds: ${SEEDS[*]}, quick=$QUICK, jobs=$JOBS" | tee -a "$LOG"
START=$SECONDS

# The job pool (JOBS): spawn FUNCTION ARGS... runs `FUNCTION ARGS` (train, evaluate...) in the
# background with nproc/JOBS threads once fewer than JOBS jobs run, or, with JOBS=1, at once in the
# foreground with all cores; drain waits for them all. A failed job stops the others and the script.
RUNNING=0
POOL_THREADS=()  # --threads for the neraf call of a job; set in its background shell only
spawn() {
  if [ "$JOBS" = 1 ]; then
    "$@"
    return
  fi
  while [ "$RUNNING" -ge "$JOBS" ]; do reap; done
  (
    POOL_THREADS=(--threads $(($(nproc) / JOBS)))
    "$@"
  ) &
  RUNNING=$((RUNNING + 1))
}
reap() {
  local rc=0
  wait -n || rc=$?
  RUNNING=$((RUNNING - 1))
  if [ "$rc" != 0 ]; then
    echo "experiments: a job failed (exit $rc); stopping the others" >&2
    exit 1
  fi
}
drain() { while [ "$RUNNING" -gt 0 ]; do reap; done; }
stop_jobs() {
  local job
  for job in $(jobs -p); do
    pkill -TERM -P "$job" 2>/dev/null || true  # its neraf (an interrupted training resumes later)
    kill "$job" 2>/dev/null || true
  done
}
trap stop_jobs EXIT
trap 'exit 130' INT # so that Ctrl-C stops the background jobs too (wait -n returns on a trapped signal)
trap 'exit 143' TERM

say() { printf '\n== %s\n' "$*" | tee -a "$LOG"; }
# timed NAME CMD...: runs neraf CMD, logging its wall time
timed() {
  local name=$1 t0=$SECONDS
  shift
  "$NERAF" "$@" "${POOL_THREADS[@]}" >>"$LOG" 2>&1 || { echo "experiments: $name failed; see $LOG" >&2; tail -n 5 "$LOG" >&2; exit 1; }
  echo "time $name $((SECONDS - t0)) s" | tee -a "$LOG"
}
# room NAME SYNTH_ARGS...: a dataset and, at the same scale, the same room heard at new
# microphone positions (NAME_novel)
room() {
  local name=$1
  shift
  [ -f "$OUT/data/$name/synth_info.json" ] ||
    timed "synth $name" synth "$@" "${MICS[@]}" --seed 1 --out "$OUT/data/$name" --force --quiet
  [ -f "$OUT/data/${name}_novel/synth_info.json" ] ||
    timed "synth ${name}_novel" synth "$@" --mics random --mic-count 40 --seed 2 \
      --gain-from "$OUT/data/$name" --out "$OUT/data/${name}_novel" --force --quiet
}
# train RUN ARGS...: neraf train --out $OUT/runs/RUN ARGS, resumed if a previous call stopped
train() {
  local run=$OUT/runs/$1
  shift
  if [ -f "$run/done" ]; then return; fi
  if [ -f "$run/config.json" ]; then
    timed "train $(basename "$run") (resumed)" train --out "$run" --resume --quiet
  else
    timed "train $(basename "$run")" train --out "$run" --force --quiet "$@"
  fi
  touch "$run/done"
}
# evaluate JSON RUN ARGS...: neraf eval of $OUT/runs/RUN into $OUT/eval/JSON.json
# A JSON is kept while it is newer than the `done` marker of every run it scores: a run trained
# after it is scored again; a deleted run folder does not force a new scoring.
evaluate() {
  local json=$OUT/eval/$1.json run=$OUT/runs/$2
  shift 2
  mkdir -p "$OUT/eval"
  local scored=("$run") ablations arg prev=
  for arg in "$@"; do
    if [ "$prev" = --ablation-runs ]; then
      IFS=, read -r -a ablations <<<"$arg"
      scored+=("${ablations[@]}")
    fi
    prev=$arg
  done
  for arg in "${scored[@]}"; do
    [ "$json" -nt "$arg/done" ] || {
      timed "eval $(basename "$json" .json)" eval --run "$run" --json "$json" --quiet "$@"
      return
    }
  done
}

# Each experiment spawns its trainings, then (once they are all done) its evaluations.
for e in $EXPERIMENTS; do
  case $e in
    1)
      say "1/5 neraf vs the baselines (default neraf train, joint)"
      case ${E1_FEATURES:-1} in
        0 | 1) ;;
        *)
          echo "experiments: E1_FEATURES takes 1 (the per-query variants, the default) or 0, not '$E1_FEATURES'" >&2
          exit 2
          ;;
      esac
      E1_ROOMS=${E1_ROOMS:-ss_demo raf_furnished}
      for r in $E1_ROOMS; do
        case $r in
          ss_demo) room ss_demo --preset demo --layout soundspaces ;;
          raf_furnished) room raf_furnished --preset furnished_room ;;
          *)
            echo "experiments: unknown E1_ROOMS room '$r' (use ss_demo, raf_furnished)" >&2
            exit 2
            ;;
        esac
        for s in "${SEEDS[@]}"; do
          a=(--data "$OUT/data/$r" --seed "$s" "${JOINT[@]}")
          spawn train "e1_${r}_s$s" "${a[@]}"
          # Issue 13 §5: the grid read per query beside the published global feature, trained
          # jointly like the default run (E1_FEATURES=0 leaves them out).
          [ "${E1_FEATURES:-1}" = 1 ] || continue
          spawn train "e1_${r}_features_local_s$s" "${a[@]}" --grid-features local
          spawn train "e1_${r}_features_both_s$s" "${a[@]}" --grid-features both
        done
      done
      drain
      # e1_evaluate ROOM SEED: both evaluations of one run, one after the other (each writes the
      # run's eval folder)
      e1_evaluate() {
        evaluate "e1_$1_s$2" "e1_$1_s$2" --novel-data "$OUT/data/$1_novel" --skip-vision
        [ "${E1_FEATURES:-1}" = 1 ] || return 0
        evaluate "e1_features_$1_s$2" "e1_$1_s$2" --novel-data "$OUT/data/$1_novel" \
          --skip-vision --no-baselines \
          --ablation-runs "$OUT/runs/e1_$1_features_local_s$2,$OUT/runs/e1_$1_features_both_s$2"
      }
      for r in $E1_ROOMS; do
        for s in "${SEEDS[@]}"; do spawn e1_evaluate "$r" "$s"; done
      done
      drain
      ;;
    2)
      say "2/5 the grid ablation (acoustic field alone on a frozen radiance field)"
      E2_ROOMS=${E2_ROOMS:-occluded raf_furnished raf_empty}
      for r in $E2_ROOMS; do
        case $r in
          occluded) room occluded --preset occluded ;;
          raf_furnished) room raf_furnished --preset furnished_room ;;
          raf_empty) room raf_empty --preset empty_room ;;
          *)
            echo "experiments: unknown E2_ROOMS room '$r' (use occluded, raf_furnished, raf_empty)" >&2
            exit 2
            ;;
        esac
        train "v_$r" --data "$OUT/data/$r" --modality vision --seed 1 "${VISION[@]}"
      done
      for r in $E2_ROOMS; do
        for s in "${SEEDS[@]}"; do
          a=(--data "$OUT/data/$r" --modality audio --vision-run "$OUT/runs/v_$r" --seed "$s"
            "${AUDIO[@]}")
          # S = 64 first: it takes 3-4x as long as the others, which then fill the other job slots
          spawn train "e2_${r}_S64_s$s" "${a[@]}" --grid-resolution 64
          spawn train "e2_${r}_full_s$s" "${a[@]}"
          spawn train "e2_${r}_grid_none_s$s" "${a[@]}" --grid none
          spawn train "e2_${r}_grid_zeros_s$s" "${a[@]}" --grid zeros
          spawn train "e2_${r}_S24_s$s" "${a[@]}" --grid-resolution 24
          spawn train "e2_${r}_features_local_s$s" "${a[@]}" --grid-features local
          spawn train "e2_${r}_features_both_s$s" "${a[@]}" --grid-features both
        done
      done
      drain
      for r in $E2_ROOMS; do
        for s in "${SEEDS[@]}"; do
          abl=$OUT/runs/e2_${r}_grid_none_s$s,$OUT/runs/e2_${r}_grid_zeros_s$s
          abl+=,$OUT/runs/e2_${r}_S24_s$s,$OUT/runs/e2_${r}_S64_s$s
          abl+=,$OUT/runs/e2_${r}_features_local_s$s,$OUT/runs/e2_${r}_features_both_s$s
          spawn evaluate "e2_${r}_s$s" "e2_${r}_full_s$s" --novel-data "$OUT/data/${r}_novel" \
            --skip-vision --ablation-runs "$abl"
        done
      done
      drain
      ;;
    3)
      say "3/5 few-shot (25 / 50 / 75 / 100 % of the training RIRs)"
      for f in ${E3_FEATURES-0.25 0.5 0.75}; do
        case $f in
          0.25 | 0.5 | 0.75) ;;
          *)
            echo "experiments: E3_FEATURES takes 0.25, 0.5 and 0.75 (100 % is experiment 2's), not '$f'" >&2
            exit 2
            ;;
        esac
      done
      # with_features F: whether the per-query variants (issue 13 §5) run at fraction F (100 % is
      # experiment 2's furnished-room table)
      with_features() { case " ${E3_FEATURES-0.25 0.5 0.75} " in *" $1 "*) return 0 ;; esac; return 1; }
      room raf_furnished --preset furnished_room
      train v_raf_furnished --data "$OUT/data/raf_furnished" --modality vision --seed 1 "${VISION[@]}"
      for s in "${SEEDS[@]}"; do
        for f in 0.25 0.5 0.75 1; do
          run=e3_raf_furnished_f${f}_s$s
          [ "$f" = 1 ] && run=e2_raf_furnished_full_s$s  # the same run as experiment 2's
          a=(--data "$OUT/data/raf_furnished" --modality audio --vision-run "$OUT/runs/v_raf_furnished"
            --seed "$s" --audio-fraction "$f" "${AUDIO[@]}")
          # A scored run is not trained again (its run folder may have been deleted for space).
          if [ ! -f "$OUT/eval/e3_raf_furnished_f${f}_s$s.json" ] || with_features "$f"; then
            spawn train "$run" "${a[@]}"
          fi
          with_features "$f" || continue
          spawn train "e3_raf_furnished_features_local_f${f}_s$s" "${a[@]}" --grid-features local
          spawn train "e3_raf_furnished_features_both_f${f}_s$s" "${a[@]}" --grid-features both
        done
      done
      drain
      # e3_evaluate FRACTION SEED: both evaluations of one run, one after the other (each writes
      # the run's eval folder)
      e3_evaluate() {
        local run=e3_raf_furnished_f$1_s$2
        [ "$1" = 1 ] && run=e2_raf_furnished_full_s$2
        evaluate "e3_raf_furnished_f$1_s$2" "$run" --skip-vision
        with_features "$1" || return 0
        evaluate "e3_features_raf_furnished_f$1_s$2" "$run" --skip-vision --no-baselines \
          --ablation-runs "$OUT/runs/e3_raf_furnished_features_local_f$1_s$2,$OUT/runs/e3_raf_furnished_features_both_f$1_s$2"
      }
      for s in "${SEEDS[@]}"; do
        for f in 0.25 0.5 0.75 1; do spawn e3_evaluate "$f" "$s"; done
      done
      drain
      ;;
    4)
      say "4/5 cross-modal vision with sparse images (10 / 20 / 40 training views)"
      room ss_demo --preset demo --layout soundspaces
      E4_VIEWS=${E4_VIEWS:-10 20 40}
      for v in $E4_VIEWS; do
        case $v in
          10 | 20 | 40) ;;
          *)
            echo "experiments: E4_VIEWS takes 10, 20 and 40 (the report's columns), not '$v'" >&2
            exit 2
            ;;
        esac
        d=$OUT/data/ss_demo_views$v
        if [ ! -f "$d/transforms.json" ]; then
          # The same room, the same held-out views; only the first V training views listed.
          /usr/bin/python3 scripts/experiments_report.py --subset-views "$OUT/data/ss_demo" "$d" "$v"
        fi
        for s in "${SEEDS[@]}"; do
          spawn train "e4_views${v}_vision_s$s" --data "$d" --modality vision --seed "$s" "${VIEWS_VISION[@]}"
          spawn train "e4_views${v}_joint_s$s" --data "$d" --seed "$s" "${VIEWS_JOINT[@]}"
        done
      done
      drain
      for v in $E4_VIEWS; do
        for s in "${SEEDS[@]}"; do
          spawn evaluate "e4_views${v}_vision_s$s" "e4_views${v}_vision_s$s" --no-baselines
          spawn evaluate "e4_views${v}_joint_s$s" "e4_views${v}_joint_s$s" --no-baselines
        done
      done
      drain
      ;;
    5)
      say "5/5 the loss study (SC+SL-MSE, the reference's, vs SC+SL-L1 vs MSE)"
      room raf_furnished --preset furnished_room
      train v_raf_furnished --data "$OUT/data/raf_furnished" --modality vision --seed 1 "${VISION[@]}"
      for s in "${SEEDS[@]}"; do
        a=(--data "$OUT/data/raf_furnished" --modality audio --vision-run "$OUT/runs/v_raf_furnished"
          --seed "$s" "${AUDIO[@]}")
        spawn train "e2_raf_furnished_full_s$s" "${a[@]}"
        spawn train "e5_raf_furnished_loss_sc_sll1_s$s" "${a[@]}" --audio-loss sc_sll1
        spawn train "e5_raf_furnished_loss_mse_s$s" "${a[@]}" --audio-loss mse
      done
      drain
      for s in "${SEEDS[@]}"; do
        spawn evaluate "e5_raf_furnished_s$s" "e2_raf_furnished_full_s$s" --skip-vision --no-baselines \
          --ablation-runs "$OUT/runs/e5_raf_furnished_loss_sc_sll1_s$s,$OUT/runs/e5_raf_furnished_loss_mse_s$s"
      done
      drain
      ;;
    *)
      echo "experiments: unknown experiment '$e' (EXPERIMENTS takes 1 to 5)" >&2
      exit 2
      ;;
  esac
done

ELAPSED=$((SECONDS - START))
echo "experiments: finished in $ELAPSED s" | tee -a "$LOG"
/usr/bin/python3 scripts/experiments_report.py --out "$OUT" "${REPORT[@]}" --seconds "$ELAPSED" \
  --command "scripts/experiments.sh$([ "$QUICK" = 1 ] && echo ' --quick')" \
  ${PROVENANCE:+--provenance "$PROVENANCE"}
