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
#   PROVENANCE=FILE scripts/...       the report's header lists the calls in FILE (Markdown)
#                                     instead of naming this call alone: for results gathered over
#                                     several partial calls (docs/results/experiments_provenance.md;
#                                     add this call to it first)
# Runs are kept in build/experiments/ and skipped when their eval JSON exists, so an interrupted
# run continues where it stopped (an unfinished training resumes from its last checkpoint).
set -euo pipefail
cd "$(dirname "$0")/.."
QUICK=0
[ "${1:-}" = "--quick" ] && QUICK=1
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
  "experiments: $EXPERIMENTS, seeds: ${SEEDS[*]}, quick=$QUICK" | tee -a "$LOG"
START=$SECONDS

say() { printf '\n== %s\n' "$*" | tee -a "$LOG"; }
# timed NAME CMD...: runs neraf CMD, logging its wall time
timed() {
  local name=$1 t0=$SECONDS
  shift
  "$NERAF" "$@" >>"$LOG" 2>&1 || { echo "experiments: $name failed; see $LOG" >&2; tail -n 5 "$LOG" >&2; exit 1; }
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
evaluate() {
  local json=$OUT/eval/$1.json run=$OUT/runs/$2
  shift 2
  mkdir -p "$OUT/eval"
  [ -f "$json" ] || timed "eval $(basename "$json" .json)" eval --run "$run" --json "$json" --quiet "$@"
}

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
      for r in ${E1_ROOMS:-ss_demo raf_furnished}; do
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
          train "e1_${r}_s$s" "${a[@]}"
          evaluate "e1_${r}_s$s" "e1_${r}_s$s" --novel-data "$OUT/data/${r}_novel" --skip-vision
          # Issue 13 §5: the grid read per query beside the published global feature, trained
          # jointly like the default run (E1_FEATURES=0 leaves them out).
          [ "${E1_FEATURES:-1}" = 1 ] || continue
          train "e1_${r}_features_local_s$s" "${a[@]}" --grid-features local
          train "e1_${r}_features_both_s$s" "${a[@]}" --grid-features both
          evaluate "e1_features_${r}_s$s" "e1_${r}_s$s" --novel-data "$OUT/data/${r}_novel" \
            --skip-vision --no-baselines \
            --ablation-runs "$OUT/runs/e1_${r}_features_local_s$s,$OUT/runs/e1_${r}_features_both_s$s"
        done
      done
      ;;
    2)
      say "2/5 the grid ablation (acoustic field alone on a frozen radiance field)"
      for r in ${E2_ROOMS:-occluded raf_furnished raf_empty}; do
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
        for s in "${SEEDS[@]}"; do
          a=(--data "$OUT/data/$r" --modality audio --vision-run "$OUT/runs/v_$r" --seed "$s"
            "${AUDIO[@]}")
          train "e2_${r}_full_s$s" "${a[@]}"
          train "e2_${r}_grid_none_s$s" "${a[@]}" --grid none
          train "e2_${r}_grid_zeros_s$s" "${a[@]}" --grid zeros
          train "e2_${r}_S24_s$s" "${a[@]}" --grid-resolution 24
          train "e2_${r}_S64_s$s" "${a[@]}" --grid-resolution 64
          train "e2_${r}_features_local_s$s" "${a[@]}" --grid-features local
          train "e2_${r}_features_both_s$s" "${a[@]}" --grid-features both
          abl=$OUT/runs/e2_${r}_grid_none_s$s,$OUT/runs/e2_${r}_grid_zeros_s$s
          abl+=,$OUT/runs/e2_${r}_S24_s$s,$OUT/runs/e2_${r}_S64_s$s
          abl+=,$OUT/runs/e2_${r}_features_local_s$s,$OUT/runs/e2_${r}_features_both_s$s
          evaluate "e2_${r}_s$s" "e2_${r}_full_s$s" --novel-data "$OUT/data/${r}_novel" \
            --skip-vision --ablation-runs "$abl"
        done
      done
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
      room raf_furnished --preset furnished_room
      train v_raf_furnished --data "$OUT/data/raf_furnished" --modality vision --seed 1 "${VISION[@]}"
      for s in "${SEEDS[@]}"; do
        for f in 0.25 0.5 0.75 1; do
          run=e3_raf_furnished_f${f}_s$s
          [ "$f" = 1 ] && run=e2_raf_furnished_full_s$s  # the same run as experiment 2's
          a=(--data "$OUT/data/raf_furnished" --modality audio --vision-run "$OUT/runs/v_raf_furnished"
            --seed "$s" --audio-fraction "$f" "${AUDIO[@]}")
          # A scored run is not trained again (its run folder may have been deleted for space).
          [ -f "$OUT/eval/e3_raf_furnished_f${f}_s$s.json" ] || train "$run" "${a[@]}"
          evaluate "e3_raf_furnished_f${f}_s$s" "$run" --skip-vision
          # Issue 13 §5: the grid read per query beside the published global feature, at the
          # fractions E3_FEATURES takes (100 % is experiment 2's furnished-room table).
          case " ${E3_FEATURES-0.25 0.5 0.75} " in *" $f "*) ;; *) continue ;; esac
          train "$run" "${a[@]}"
          train "e3_raf_furnished_features_local_f${f}_s$s" "${a[@]}" --grid-features local
          train "e3_raf_furnished_features_both_f${f}_s$s" "${a[@]}" --grid-features both
          evaluate "e3_features_raf_furnished_f${f}_s$s" "$run" --skip-vision --no-baselines \
            --ablation-runs "$OUT/runs/e3_raf_furnished_features_local_f${f}_s$s,$OUT/runs/e3_raf_furnished_features_both_f${f}_s$s"
        done
      done
      ;;
    4)
      say "4/5 cross-modal vision with sparse images (10 / 20 / 40 training views)"
      room ss_demo --preset demo --layout soundspaces
      for v in ${E4_VIEWS:-10 20 40}; do
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
          train "e4_views${v}_vision_s$s" --data "$d" --modality vision --seed "$s" "${VIEWS_VISION[@]}"
          train "e4_views${v}_joint_s$s" --data "$d" --seed "$s" "${VIEWS_JOINT[@]}"
          evaluate "e4_views${v}_vision_s$s" "e4_views${v}_vision_s$s" --no-baselines
          evaluate "e4_views${v}_joint_s$s" "e4_views${v}_joint_s$s" --no-baselines
        done
      done
      ;;
    5)
      say "5/5 the loss study (SC+SL-MSE, the reference's, vs SC+SL-L1 vs MSE)"
      room raf_furnished --preset furnished_room
      train v_raf_furnished --data "$OUT/data/raf_furnished" --modality vision --seed 1 "${VISION[@]}"
      for s in "${SEEDS[@]}"; do
        a=(--data "$OUT/data/raf_furnished" --modality audio --vision-run "$OUT/runs/v_raf_furnished"
          --seed "$s" "${AUDIO[@]}")
        train "e2_raf_furnished_full_s$s" "${a[@]}"
        train "e5_raf_furnished_loss_sc_sll1_s$s" "${a[@]}" --audio-loss sc_sll1
        train "e5_raf_furnished_loss_mse_s$s" "${a[@]}" --audio-loss mse
        evaluate "e5_raf_furnished_s$s" "e2_raf_furnished_full_s$s" --skip-vision --no-baselines \
          --ablation-runs "$OUT/runs/e5_raf_furnished_loss_sc_sll1_s$s,$OUT/runs/e5_raf_furnished_loss_mse_s$s"
      done
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
