#!/usr/bin/env bash
# Bad input FILES on every command (bad_flags.sh does the flag values): truncated, foreign,
# empty, NaN/Inf/huge audio (WAV, FLAC), PNGs cut short, .npy magnitudes, transforms.json,
# points.txt, RAF poses, split files, scene / path / pose-list JSON, run folders with a missing or
# damaged config.json / data.json / checkpoint, model files, folders and pipes where files are
# expected. Each must exit 1 or 2 within 60 s, print one "error:" line naming the file (for
# `info`: exactly one problem naming it, plus its closing summary line), and leave nothing behind
# (no output, no feature cache, no temporary file). Dataset damage is tried on both `info` and
# `train`: what info accepts, training accepts.
# Usage: bad_input.sh <path to neraf> <assets dir>
set -u
NERAF=$1
ASSETS=$2
source "$(dirname "$0")/lib.sh"

WAV="$ASSETS/real/rir_clap.wav"
DRY="$ASSETS/real/castanets_dry.wav"
BASE="$TMP/base"
mkdir -p "$BASE"
classes=0
case_no=0

# --- base data: tiny datasets (SoundSpaces + images, RAF, another room), a tiny run, a model ---
quiet() { "$@" >"$TMP/setup.log" 2>&1 || { cat "$TMP/setup.log"; echo "setup failed: $*"; exit 1; }; }
quiet "$NERAF" synth --preset demo --layout soundspaces --mics random --mic-count 2 --seed 3 \
  --out "$BASE/ss" --quiet
quiet "$NERAF" synth --preset demo --layout raf --mics random --mic-count 2 --seed 3 \
  --out "$BASE/raf" --quiet
quiet "$NERAF" synth --preset shoebox --layout soundspaces --mics random --mic-count 2 --seed 5 \
  --out "$BASE/other_room" --quiet
quiet "$NERAF" train --data "$BASE/ss" --out "$BASE/run" --steps 2 --audio-start-step 0 \
  --rays 128 --quiet
quiet "$NERAF" export --run "$BASE/run" --out "$BASE/model.nrf"
# The dataset copies below must not inherit the run's feature cache.
rm -rf "$BASE/ss/.neraf_cache"

# python3 helpers: damaged files written byte by byte (no numpy needed).
py() { python3 - "$@"; }
# float_wav PATH RATE CHANNELS VALUE_AT_100 [DECLARED_FRAMES]: 2000 frames of 0.01, one odd value
float_wav() {
  py "$@" <<'PY'
import struct, sys
path, rate, ch, odd = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
declared = int(sys.argv[5]) if len(sys.argv) > 5 else None
n = 2000 if declared is None else 5
x = [0.01] * (n * ch)
if n > 100: x[100 * ch] = odd
frames = declared if declared is not None else n
data = struct.pack("<%df" % len(x), *x)
hdr = b"RIFF" + struct.pack("<I", 36 + frames * ch * 4) + b"WAVEfmt " + struct.pack(
    "<IHHIIHH", 16, 3, ch, rate, rate * ch * 4, ch * 4, 32) + b"data" + struct.pack("<I", frames * ch * 4)
open(path, "wb").write(hdr + data)
PY
}
# npy PATH T VALUE_AT_300: a [2, 257, T] float32 magnitude file (0.5 everywhere, one odd value)
npy() {
  py "$@" <<'PY'
import struct, sys
path, t, odd = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
d = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 257, %d), }" % t
d += " " * ((64 - (10 + len(d) + 1) % 64) % 64) + "\n"
v = [0.5] * (2 * 257 * t)
v[300] = odd
open(path, "wb").write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(d)) + d.encode() +
                       struct.pack("<%df" % len(v), *v))
PY
}
# cut FILE: keep the first half of its bytes
cut_half() { local n; n=$(stat -c %s "$1"); head -c $((n / 2)) "$1" >"$1.half" && mv "$1.half" "$1"; }
# json_set FILE PYTHON_EXPR: rewrite a JSON file through `d` (python)
json_edit() {
  py "$1" "$2" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
exec(sys.argv[2])
open(sys.argv[1], "w").write(json.dumps(d))
PY
}

# fresh NAME SRC: a copy of base dataset/run SRC as $D (damage it, then call bad)
fresh() { D="$TMP/c_$1"; rm -rf "$D"; cp -r "$BASE/$2" "$D"; }
# out: a fresh output path under $O that must not exist after a refused command
next_out() { case_no=$((case_no + 1)); O="$TMP/o_$case_no"; }

# check WHAT NAME MODE: the last command (output in $TMP/out, $TMP/err, exit code $got) failed
# cleanly. MODE info: the problem lines ("error: ...") are one naming NAME plus the summary.
check() {
  local what=$1 name=$2 mode=$3
  if [ "$got" -eq 124 ]; then
    fail "$what: still running after 60 s"
  elif [ "$got" -ne 1 ] && [ "$got" -ne 2 ]; then
    fail "$what: exited $got, expected 1 or 2; stderr: $(tail -c 300 "$TMP/err")"
  fi
  local n
  n=$(grep -c '^error:' "$TMP/err")
  if [ "$mode" = info ]; then
    # One problem per line (a damaged points.txt also orphans the split entries using it), the
    # first naming the file, then the summary line.
    [ "$n" -ge 2 ] ||
      fail "$what: $n error lines, expected problems + summary: $(head -c 600 "$TMP/err")"
    tail -n 1 "$TMP/err" | grep -q "error(s) found" || fail "$what: no summary line"
  else
    [ "$n" -eq 1 ] || fail "$what: $n error lines, expected 1: $(head -c 600 "$TMP/err")"
  fi
  grep '^error:' "$TMP/err" | head -n 1 | grep -qF -- "$name" ||
    fail "$what: the error does not name '$name': $(grep '^error:' "$TMP/err" | head -c 400)"
  if grep -q "bad_alloc\|terminate called\|Exception raised from" "$TMP/err"; then
    fail "$what: raw library text: $(head -c 300 "$TMP/err")"
  fi
  [ -e "$O" ] && fail "$what: left $O behind"
  if [ -n "${D:-}" ] && [ -e "$D" ]; then
    local left
    left=$(find "$D" -name '.neraf_cache' -o -name '*.tmp-*' | head -n 3)
    [ -z "$left" ] || fail "$what: left $left behind"
  fi
}
run() { timeout 60 "$@" >"$TMP/out" 2>"$TMP/err"; got=$?; }

# bad NAME CMD...: one class of bad input to a command other than info
bad() {
  local name=$1; shift
  classes=$((classes + 1))
  next_out
  local cmd=("${@//@OUT@/$O}")
  run "${cmd[@]}"
  check "${cmd[*]#"$NERAF" }" "$name" cmd
}
# bad_data NAME: the damaged dataset $D is refused by info (one problem naming NAME) and by train
bad_data() {
  local name=$1
  classes=$((classes + 1))
  next_out
  run "$NERAF" info --no-t60 "$D"
  check "info ${D#"$TMP/"} ($name)" "$name" info
  run "$NERAF" train --data "$D" --out "$O" --steps 2 --audio-start-step 0 --rays 64 --quiet
  check "train on ${D#"$TMP/"} ($name)" "$name" cmd
}

SSW=binaural_rirs/0   # a folder of SoundSpaces RIRs of the base set
first_ss_wav() { ls "$D/$SSW"/*.wav | head -n 1; }
RAFW=data/000001/rir.wav

# --- audio files of a dataset ---------------------------------------------------------------
fresh trunc raf; float_wav "$D/$RAFW" 48000 1 0 48000  # the header promises 48000, 5 present
bad_data "$RAFW"
fresh half_wav ss; W=$(first_ss_wav); cut_half "$W"
bad_data "${W#"$D/"}"
fresh empty_wav raf; : >"$D/$RAFW"
bad_data "$RAFW"
fresh foreign_wav raf; echo "meeting notes, not a recording" >"$D/$RAFW"
bad_data "$RAFW"
fresh png_as_wav ss; W=$(first_ss_wav); cp "$(ls "$D"/images/*.png | head -n 1)" "$W"
bad_data "${W#"$D/"}"
fresh nan_wav raf; float_wav "$D/$RAFW" 48000 1 nan
bad_data "$RAFW"
fresh inf_wav ss; W=$(first_ss_wav); float_wav "$W" 44100 2 inf
bad_data "${W#"$D/"}"
fresh huge_wav raf; float_wav "$D/$RAFW" 48000 1 1e30
bad_data "$RAFW"
fresh rate_wav raf; float_wav "$D/$RAFW" 44100 1 0.5
bad_data "$RAFW"
fresh dir_wav raf; rm "$D/$RAFW"; mkdir "$D/$RAFW"
bad_data "$RAFW"
fresh fifo_wav raf; rm "$D/$RAFW"; mkfifo "$D/$RAFW"
bad_data "$RAFW"
fresh long_wav ss; W=$(first_ss_wav)
py "$W" <<'PY'
import struct, sys  # 40 s binaural at 44.1 kHz: longer than any impulse response
n = 40 * 44100 * 2
hdr = b"RIFF" + struct.pack("<I", 36 + n * 4) + b"WAVEfmt " + struct.pack(
    "<IHHIIHH", 16, 3, 2, 44100, 44100 * 8, 8, 32) + b"data" + struct.pack("<I", n * 4)
open(sys.argv[1], "wb").write(hdr + struct.pack("<f", 0.01) * n)
PY
bad_data "${W#"$D/"}"
grep -q "GB feature cache" "$TMP/err" || fail "long RIR: no cache estimate: $(cat "$TMP/err")"

# --- SoundSpaces magnitude files (every RIR needs one for them to be used) ------------------
with_npy() {  # with_npy NAME: $D = the SoundSpaces set with a clean .npy per RIR
  fresh "$1" ss
  local w rel
  for w in "$D"/binaural_rirs/*/*.wav; do
    rel=${w#"$D/binaural_rirs/"}
    mkdir -p "$D/binaural_magnitudes_sr22050/$(dirname "$rel")"
    npy "$D/binaural_magnitudes_sr22050/${rel%.wav}.npy" 5 0.5
  done
  NPY=$(ls "$D"/binaural_magnitudes_sr22050/0/*.npy | head -n 1)
  NPY=${NPY#"$D/"}
}
with_npy npy_ok
run "$NERAF" info --no-t60 "$D"
[ "$got" -eq 0 ] || fail "info on clean .npy magnitudes exited $got: $(tail -c 300 "$TMP/err")"
with_npy npy_nan; npy "$D/$NPY" 5 nan
bad_data "$NPY"
with_npy npy_negative; npy "$D/$NPY" 5 -1
bad_data "$NPY"
with_npy npy_half; cut_half "$D/$NPY"
bad_data "$NPY"
with_npy npy_foreign; echo "not numpy" >"$D/$NPY"
bad_data "$NPY"
with_npy npy_shape
py "$D/$NPY" <<'PY'
import struct, sys  # shape (3, 257, 5): one channel too many
d = "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 257, 5), }"
d += " " * ((64 - (10 + len(d) + 1) % 64) % 64) + "\n"
open(sys.argv[1], "wb").write(b"\x93NUMPY\x01\x00" + struct.pack("<H", len(d)) + d.encode() +
                              struct.pack("<f", 0.5) * (3 * 257 * 5))
PY
bad_data "$NPY"

# --- pose and split files -------------------------------------------------------------------
fresh points_huge ss; sed -i '1s/^\([0-9]*\)\t[^\t]*/\1\t1e300/' "$D/metadata/points.txt"
bad_data metadata/points.txt
fresh points_text ss; sed -i '1s/.*/0\tone\ttwo\tthree/' "$D/metadata/points.txt"
bad_data metadata/points.txt
fresh points_missing ss; rm "$D/metadata/points.txt"; mkdir "$D/metadata/points.txt"
bad_data metadata/points.txt
fresh split_json ss; echo '{"train": [' >"$D/metadata_AudioNeRF/split.json"
bad_data metadata_AudioNeRF/split.json
fresh split_dup ss; json_edit "$D/metadata_AudioNeRF/split.json" 'd["train"].append(d["train"][0])'
bad_data metadata_AudioNeRF/split.json
fresh split_shape ss; echo '{"train": "0/1_2", "test": []}' >"$D/metadata_AudioNeRF/split.json"
bad_data metadata_AudioNeRF/split.json
fresh rx_huge raf; echo "1.0,1e300,2.0" >"$D/data/000001/rx_pos.txt"
bad_data data/000001/rx_pos.txt
fresh tx_nan raf; echo "0,0.7071,0,0.7071,nan,1.5,1.0" >"$D/data/000001/tx_pos.txt"
bad_data data/000001/tx_pos.txt
fresh tx_short raf; echo "0,0,0" >"$D/data/000001/tx_pos.txt"
bad_data data/000001/tx_pos.txt
fresh raf_split raf; echo '{"train": [], "test": [[1]]}' >"$D/metadata/data-split.json"
bad_data metadata/data-split.json

# --- images and transforms.json -------------------------------------------------------------
IMG=$(cd "$BASE/ss" && ls images/*.png | head -n 1)
fresh png_half ss; cut_half "$D/$IMG"
bad_data "$IMG"
fresh png_foreign ss; echo "not an image" >"$D/$IMG"
bad_data "$IMG"
fresh png_missing ss; rm "$D/$IMG"
bad_data "$IMG"
fresh tf_json ss; echo '{"frames": [' >"$D/transforms.json"
bad_data transforms.json
fresh tf_empty ss; : >"$D/transforms.json"
bad_data transforms.json
fresh tf_dup ss; json_edit "$D/transforms.json" 'd["frames"].append(dict(d["frames"][0]))'
bad_data transforms.json
fresh tf_far ss; json_edit "$D/transforms.json" 'd["frames"][0]["transform_matrix"][0][3] = 1e300'
bad_data transforms.json
fresh tf_nan ss; json_edit "$D/transforms.json" 'd["frames"][1]["transform_matrix"][1][2] = 4242.25'
sed -i 's/4242.25/NaN/' "$D/transforms.json"  # as Python's json.dump writes a NaN
bad_data transforms.json

# Silence is legitimate (SoundSpaces ships silent RIRs): a warning info counts, training accepts.
fresh zero_wav raf
py "$D/$RAFW" <<'PY'
import struct, sys  # 0.5 s of 0.0
n = 24000
hdr = b"RIFF" + struct.pack("<I", 36 + n * 4) + b"WAVEfmt " + struct.pack(
    "<IHHIIHH", 16, 3, 1, 48000, 48000 * 4, 4, 32) + b"data" + struct.pack("<I", n * 4)
open(sys.argv[1], "wb").write(hdr + bytes(n * 4))
PY
run "$NERAF" info --no-t60 "$D"
[ "$got" -eq 0 ] || fail "info on a silent RIR exited $got"
grep -q "^warning: .*$RAFW: every sample is zero" "$TMP/err" || fail "silent RIR: no warning"
expect_in "$TMP/out" "0 error(s), 1 warning(s)"

# --- runs: a vision run of another room, damaged run folders --------------------------------
D=""
bad "$BASE/run" "$NERAF" train --data "$BASE/other_room" --modality audio --vision-run "$BASE/run" \
  --steps 2 --out @OUT@ --quiet
# The same image names and poses with other pictures (each image swapped for the next one).
fresh repainted ss
mapfile -t pictures < <(ls "$D"/images/*.png)
cp "${pictures[0]}" "$TMP/first.png"
for ((i = 0; i + 1 < ${#pictures[@]}; ++i)); do cp "${pictures[i + 1]}" "${pictures[i]}"; done
cp "$TMP/first.png" "${pictures[-1]}"
bad "training pictures" "$NERAF" train --data "$D" --modality audio --vision-run "$BASE/run" \
  --steps 2 --out @OUT@ --quiet
D=""
fresh run_noconfig run; rm "$D/config.json"
bad "$D" "$NERAF" eval --run "$D" --json @OUT@.json --quiet
fresh run_badconfig run; echo '{"preset": ' >"$D/config.json"
bad "$D/config.json" "$NERAF" render view --run "$D" --frame 0 --out @OUT@.png
fresh run_confdir run; rm "$D/config.json"; mkdir "$D/config.json"
bad "$D" "$NERAF" export --run "$D" --out @OUT@.nrf
fresh run_nodata run; rm "$D/data.json"
bad "$D/data.json" "$NERAF" render view --run "$D" --frame 0 --out @OUT@.png
fresh run_baddata run; echo '[1, 2' >"$D/data.json"
bad "$D/data.json" "$NERAF" eval --run "$D" --json @OUT@.json --quiet
CK=$(ls "$BASE/run/checkpoints/"step-*.pt | grep -v calibration | tail -n 1)
CK=${CK#"$BASE/run/"}
fresh run_cut_ckpt run; for f in "$D"/checkpoints/step-*.pt; do cut_half "$f"; done
bad "$D/checkpoints" "$NERAF" render view --run "$D" --frame 0 --out @OUT@.png
D=""

# --- model files ----------------------------------------------------------------------------
cp "$BASE/model.nrf" "$TMP/half.nrf"; cut_half "$TMP/half.nrf"
bad "$TMP/half.nrf" "$NERAF" render rir --model "$TMP/half.nrf" --mic 2,1.5,2.5 --src 1.1,1.2,0.9 \
  --out @OUT@
echo "not a model" >"$TMP/foreign.nrf"
bad "$TMP/foreign.nrf" "$NERAF" eval --model "$TMP/foreign.nrf" --data "$BASE/ss" --json @OUT@.json \
  --quiet

# --- audio given to metrics / auralize (WAV, FLAC) -------------------------------------------
float_wav "$TMP/nan.wav" 48000 1 nan
bad "$TMP/nan.wav" "$NERAF" metrics --rir "$TMP/nan.wav"
quiet "$NERAF" auralize --rir "$WAV" --in "$DRY" --out "$TMP/good.flac"
cp "$TMP/good.flac" "$TMP/half.flac"; cut_half "$TMP/half.flac"
bad "$TMP/half.flac" "$NERAF" metrics --pred "$TMP/half.flac" --gt "$WAV"
: >"$TMP/empty.wav"
bad "$TMP/empty.wav" "$NERAF" auralize --rir "$WAV" --in "$TMP/empty.wav" --out @OUT@
float_wav "$TMP/inf_dry.wav" 48000 1 -inf
bad "$TMP/inf_dry.wav" "$NERAF" auralize --rir "$WAV" --in "$TMP/inf_dry.wav" --out @OUT@
float_wav "$TMP/trunc_rir.wav" 48000 1 0 48000
bad "$TMP/trunc_rir.wav" "$NERAF" auralize --rir "$TMP/trunc_rir.wav" --in "$DRY" --out @OUT@
mkfifo "$TMP/pipe.wav"
bad "$TMP/pipe.wav" "$NERAF" metrics --rir "$TMP/pipe.wav"

# --- scene, path and pose-list JSON ---------------------------------------------------------
echo '{"room": {"size": [5, 3,' >"$TMP/scene.json"
bad "$TMP/scene.json" "$NERAF" synth --scene "$TMP/scene.json" --out @OUT@ --quiet
"$NERAF" synth --preset demo --print-scene >"$TMP/scene_ok.json" 2>/dev/null
json_edit "$TMP/scene_ok.json" 'd["room"] = "large"'
bad "$TMP/scene_ok.json" "$NERAF" synth --scene "$TMP/scene_ok.json" --out @OUT@ --quiet
echo '{"version": 1, "keyframes": [{"time": 0, "mic": [1, 1.5]' >"$TMP/path.json"
bad "$TMP/path.json" "$NERAF" render trajectory --run "$BASE/run" --path "$TMP/path.json" \
  --in "$DRY" --out @OUT@
echo '{"version": 1, "poses": [{"mic": [2, 1.5, 2.5], "yaw": "north"}]}' >"$TMP/poses.json"
bad "$TMP/poses.json" "$NERAF" render rir --run "$BASE/run" --poses "$TMP/poses.json" --out @OUT@
: >"$TMP/empty_poses.json"
bad "$TMP/empty_poses.json" "$NERAF" render rir --model "$BASE/model.nrf" \
  --poses "$TMP/empty_poses.json" --out @OUT@

# --- a file where a folder is expected, and the reverse -------------------------------------
bad "$WAV" "$NERAF" train --data "$WAV" --out @OUT@ --steps 2 --audio-start-step 0 --quiet
bad "$WAV" "$NERAF" eval --run "$WAV" --json @OUT@.json --quiet
bad "$ASSETS" "$NERAF" metrics --rir "$ASSETS"

# --- an output that is one of the command's inputs or a file of the run it reads -------------
cp "$DRY" "$TMP/own_dry.wav"
cp "$BASE/model.nrf" "$TMP/own_model.nrf"
bad "--in" "$NERAF" auralize --rir "$WAV" --in "$TMP/own_dry.wav" --out "$TMP/own_dry.wav"
cmp -s "$DRY" "$TMP/own_dry.wav" || fail "auralize --out = --in changed the dry file"
bad "--rir" "$NERAF" auralize --rir "$TMP/own_dry.wav" --in "$DRY" --out "$TMP/own_dry.wav"
bad "config.json" "$NERAF" eval --run "$BASE/run" --json "$BASE/run/config.json" --skip-vision
bad "checkpoints folder" "$NERAF" export --run "$BASE/run" \
  --out "$(ls "$BASE"/run/checkpoints/step-*[0-9].pt | tail -1)"
bad "--depth" "$NERAF" render view --run "$BASE/run" --frame 0 --out "$TMP/same.png" \
  --depth "$TMP/same.png"
bad "--model" "$NERAF" render loudness --model "$TMP/own_model.nrf" --src 1.1,1.2,0.9 \
  --out "$TMP/own_model.nrf"
cmp -s "$BASE/model.nrf" "$TMP/own_model.nrf" || fail "render loudness --out = --model changed the model"
bad "--in" "$NERAF" render trajectory --model "$BASE/model.nrf" \
  --path "$ASSETS/../examples/paths/demo_walk.json" --in "$TMP/own_dry.wav" --out "$TMP/own_dry.wav"
bad "not .mp3" "$NERAF" auralize --rir "$WAV" --in "$DRY" --out @OUT@.mp3
bad "--ablation-runs" "$NERAF" eval --run "$BASE/run" --json @OUT@.json --skip-vision \
  --ablation-runs "$BASE/run,$BASE/run"
# An exported model records no training config, so no ablation can be checked against it.
bad "needs --run" "$NERAF" eval --model "$BASE/model.nrf" --json @OUT@.json --ablation-runs "$BASE/run"
# A checkpoint copied in under another step's name, a gain from a set of the other layout, a
# JSON key given twice.
last=$(ls "$BASE"/run/checkpoints/step-*[0-9].pt | tail -1)
cp "$last" "$BASE/run/checkpoints/step-000099999.pt"
bad "step-000099999.pt" "$NERAF" render rir --run "$BASE/run" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out @OUT@
rm "$BASE/run/checkpoints/step-000099999.pt"
bad "--gain-from" "$NERAF" synth --preset demo --layout soundspaces --gain-from "$BASE/raf" \
  --out @OUT@ --quiet
echo '{"room": {"size": [4, 3, 5], "size": [9, 9, 9]}}' >"$TMP/twice.json"
bad "appears twice" "$NERAF" synth --scene "$TMP/twice.json" --out @OUT@ --quiet
# --force restarts a run, never turns another folder into one; outputs that cannot be written
# fail before the work (a name too long, /proc, a deleted working folder).
bad "not a neraf run folder" "$NERAF" train --data "$BASE/ss" --out "$BASE/ss/images" --force \
  --steps 2 --audio-start-step 0 --quiet
[ -e "$BASE/ss/images/config.json" ] && fail "train --force wrote into a dataset's images folder"
# ... and synth --force replaces only a dataset synth wrote, never a run.
bad "not a dataset written by neraf synth" "$NERAF" synth --preset demo --layout raf \
  --out "$BASE/run" --force --quiet
[ -e "$BASE/run/config.json" ] || fail "synth --force deleted a run"
long=$(printf 'n%.0s' $(seq 1 250))
bad "shorter name" "$NERAF" synth --preset demo --layout raf --out "$TMP/$long" --quiet
bad "/proc" "$NERAF" export --run "$BASE/run" --out /proc/neraf_model.nrf
mkdir -p "$TMP/gone"
(cd "$TMP/gone" && rmdir "$TMP/gone" &&
  timeout 60 "$NERAF" synth --preset demo --layout raf --out ds --quiet >"$TMP/out" 2>"$TMP/err")
got=$?
classes=$((classes + 1))
next_out
check "synth in a deleted working folder" "cannot create files" cmd
# Another run's checkpoint (a copy of the run elsewhere): refused by every command that takes
# --checkpoint, and calibrate does not write into the other run.
cp -r "$BASE/run" "$TMP/other_run"
OTHER_CK=$(ls "$TMP"/other_run/checkpoints/step-*[0-9].pt | tail -n 1)
bad "not a checkpoint of the run" "$NERAF" calibrate --run "$BASE/run" --checkpoint "$OTHER_CK"
bad "not a checkpoint of the run" "$NERAF" eval --run "$BASE/run" --checkpoint "$OTHER_CK" \
  --json @OUT@.json --skip-vision --no-baselines --quiet
bad "not a checkpoint of the run" "$NERAF" export --run "$BASE/run" --checkpoint "$OTHER_CK" \
  --out @OUT@.nrf
bad "not a checkpoint of the run" "$NERAF" render view --run "$BASE/run" --checkpoint "$OTHER_CK" \
  --frame 0 --out @OUT@.png
# A room given twice to a multi-scene run, a run as its own ablation, nothing left to evaluate,
# a pose for a --rir file, outputs named for another format.
bad "given twice" "$NERAF" train --modality audio --data "$BASE/ss" --data "$BASE/ss/" \
  --vision-run "$BASE/run" --vision-run "$BASE/run" --out @OUT@ --steps 2 --quiet
bad "is --run itself" "$NERAF" eval --run "$BASE/run" --ablation-runs "$BASE/run" --json @OUT@.json \
  --skip-vision --no-baselines --quiet
quiet "$NERAF" train --data "$BASE/ss" --modality vision --out "$TMP/vision_only" --steps 2 \
  --rays 128 --quiet
bad "nothing to evaluate" "$NERAF" eval --run "$TMP/vision_only" --json @OUT@.json --skip-vision --quiet
bad "--yaw" "$NERAF" auralize --rir "$WAV" --yaw 90 --in "$DRY" --out @OUT@.wav
bad ".png" "$NERAF" render view --run "$BASE/run" --frame 0 --out @OUT@.jpg
bad ".nrf" "$NERAF" export --run "$BASE/run" --out @OUT@.wav

# --- fresh probe round b (docs/results/fresh_probes_2026-12-03b.md): each finding's class ------
rm -rf "$BASE/ss/.neraf_cache"  # made by the runs above; a copy must not inherit it
fresh tf_twice ss
py "$D/transforms.json" <<'PY'
import sys
text = open(sys.argv[1]).read()
open(sys.argv[1], "w").write(text.replace("{", '{"camera_model": "OPENCV", "camera_model": "OPENCV", ', 1))
PY
bad_data "appears twice"
D=""
# P01 outputs into the run's own dataset (or --data / --novel-data) are refused, the file intact.
cp "$BASE/ss/transforms.json" "$TMP/transforms_before.json"
bad "is inside" "$NERAF" eval --run "$BASE/run" --json "$BASE/ss/transforms.json" --skip-vision \
  --no-baselines --quiet
cmp -s "$TMP/transforms_before.json" "$BASE/ss/transforms.json" ||
  fail "eval --json into the dataset changed transforms.json"
bad "is inside" "$NERAF" render rir --run "$BASE/run" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out "$BASE/ss/$SSW/new.wav"
[ -e "$BASE/ss/$SSW/new.wav" ] && fail "render rir wrote into the run's dataset"
bad "is inside" "$NERAF" render loudness --run "$BASE/run" --src 1.1,1.2,0.9 --out @OUT@.png \
  --csv "$BASE/ss/metadata.csv"
bad "is inside" "$NERAF" eval --run "$BASE/run" --json @OUT@.json --images "$BASE/run/checkpoints" \
  --skip-vision --no-baselines --quiet
# P02 a --max-len far beyond every training RIR (it padded 37 frames to 100000 for minutes).
rm -rf "$BASE/ss/.neraf_cache"
fresh max_len ss
bad "--max-len 100000" "$NERAF" train --data "$D" --out @OUT@ --steps 2 --max-len 100000 \
  --audio-start-step 0 --rays 64 --quiet
D=""
# P03/P24 --frames checked before anything is rendered.
bad "--frames" "$NERAF" render trajectory --run "$BASE/run" --path "$TMP/path.json" --in "$DRY" \
  --out @OUT@ --frames @OUT@
# P04-P06, P26 outputs that name no file, empty values.
bad "ends in '/'" "$NERAF" render rir --run "$BASE/run" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out @OUT@/
bad "--out" "$NERAF" render rir --run "$BASE/run" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --out ""
bad "--checkpoint" "$NERAF" render rir --run "$BASE/run" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --checkpoint "" --out @OUT@
bad "--plan-only" "$NERAF" synth --preset demo --plan-only "" --quiet
bad "standard output" "$NERAF" render rir --run "$BASE/run" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out -
[ -e - ] && { rm -f -- -; fail "render rir --out - wrote a file named '-'"; }
# P07 a key given twice in a pose list, a path, a transforms.json.
echo '{"version": 1, "source": [1.1, 1.2, 0.9], "poses": [{"mic": [2, 1.5, 2.5], "mic": [2, 1.5, 2.4], "yaw": 0}]}' \
  >"$TMP/twice_poses.json"
bad "appears twice" "$NERAF" render rir --model "$BASE/model.nrf" --poses "$TMP/twice_poses.json" \
  --out @OUT@
# P08 a camera file with a misspelt or fractional size.
python3 - "$BASE/run/data.json" "$TMP/cam_typo.json" "$TMP/cam_frac.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
c2w = m["eval_camera_to_world"][0]
json.dump({"camera_to_world": c2w, "intrinsics": {"widht": 16}}, open(sys.argv[2], "w"))
json.dump({"camera_to_world": c2w, "intrinsics": {"width": 16.5}}, open(sys.argv[3], "w"))
PY
bad "unknown key" "$NERAF" render view --run "$BASE/run" --pose "$TMP/cam_typo.json" --out @OUT@.png
bad "whole numbers" "$NERAF" render view --run "$BASE/run" --pose "$TMP/cam_frac.json" \
  --out @OUT@.png
# P09-P11 flags that do not apply.
bad ".png" "$NERAF" synth --preset demo --plan-only @OUT@.jpg
bad "--hrtf" "$NERAF" synth --preset demo --layout raf --hrtf "$TMP/none.sofa" --out @OUT@ --quiet
bad "--decay-loss" "$NERAF" train --data "$BASE/ss" --modality vision --decay-loss 5 --out @OUT@ \
  --steps 2 --quiet
bad "--grid-resolution" "$NERAF" train --data "$BASE/ss" --grid none --grid-resolution 64 \
  --out @OUT@ --steps 2 --quiet
bad "--position-max-freq-exp" "$NERAF" train --data "$BASE/ss" --modality vision \
  --position-max-freq-exp 3 --out @OUT@ --steps 2 --quiet
bad "--decay-heads" "$NERAF" train --data "$BASE/ss" --modality vision --decay-heads \
  --out @OUT@ --steps 2 --quiet
bad "--grid-features" "$NERAF" train --data "$BASE/ss" --grid none --grid-features local \
  --out @OUT@ --steps 2 --quiet
bad "--grid-features" "$NERAF" train --data "$BASE/ss" --modality vision --grid-features both \
  --out @OUT@ --steps 2 --quiet
# A run whose acoustic field has decay heads, which the runtime does not evaluate.
quiet "$NERAF" train --data "$BASE/ss" --out "$TMP/decay_run" --steps 2 --audio-start-step 0 \
  --rays 128 --decay-heads --quiet
rm -rf "$BASE/ss/.neraf_cache"  # as above: later copies of the dataset must not inherit it
bad "--decay-heads" "$NERAF" export --run "$TMP/decay_run" --out @OUT@.nrf
# P12 the run's own dataset as "new positions".
bad "own dataset" "$NERAF" eval --run "$BASE/run" --novel-data "$BASE/ss" --json @OUT@.json \
  --skip-vision --no-baselines --quiet
# P13/P14 a damaged config.json / data.json value names the file.
fresh run_chunk0 run; json_edit "$D/config.json" 'd["eval_rays_per_chunk"] = 0'
bad "$D/config.json" "$NERAF" render view --run "$D" --frame 0 --out @OUT@.png
fresh run_hop0 run; json_edit "$D/data.json" 'd["audio"]["hop_length"] = 0'
bad "$D/data.json" "$NERAF" render rir --run "$D" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --out @OUT@
fresh run_nfft7 run; json_edit "$D/data.json" 'd["audio"]["n_fft"] = 7'
bad "$D/data.json" "$NERAF" render rir --run "$D" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --out @OUT@
# P17 a checkpoint name that is a folder.
fresh run_ckdir run; mkdir "$D/checkpoints/step-000099999.pt"
bad "step-000099999.pt" "$NERAF" render rir --run "$D" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out @OUT@
D=""
# P15/P22 launch: a process count that cannot split the batches, train's flags without "--".
bad "-n 3" "$NERAF" launch -n 3 -- train --data "$BASE/ss" --out @OUT@ --steps 1 --quiet
bad "put --" "$NERAF" launch -n 2 train --data "$BASE/ss" --out @OUT@ --steps 1 --quiet
# P19 a dry signal whose rate cannot be resampled names --in.
float_wav "$TMP/dry_1hz.wav" 1 1 0.5
bad "--in $TMP/dry_1hz.wav" "$NERAF" auralize --rir "$WAV" --in "$TMP/dry_1hz.wav" --out @OUT@.wav
# --- probe round c (docs/results/fresh_probes_2026-12-04.md), fixed in session 12 ---
# F05/F15 a scene where no sound reaches a microphone in time, absurd acoustics (also --dry-run).
"$NERAF" synth --preset demo --print-scene >"$TMP/demo_scene.json"
cp "$TMP/demo_scene.json" "$TMP/sc_slow.json"; json_edit "$TMP/sc_slow.json" 'd["acoustics"]["speed_of_sound"] = 1; d["acoustics"]["rir_length_s"] = 0.05'
bad "$TMP/sc_slow.json" "$NERAF" synth --scene "$TMP/sc_slow.json" --out @OUT@ --quiet
bad "$TMP/sc_slow.json" "$NERAF" synth --scene "$TMP/sc_slow.json" --dry-run
cp "$TMP/demo_scene.json" "$TMP/sc_sos.json"; json_edit "$TMP/sc_sos.json" 'd["acoustics"]["speed_of_sound"] = 1e-9'
bad "$TMP/sc_sos.json" "$NERAF" synth --scene "$TMP/sc_sos.json" --dry-run
cp "$TMP/demo_scene.json" "$TMP/sc_yaw.json"; json_edit "$TMP/sc_yaw.json" 'd["sources"][0]["yaw_deg"] = 1e308'
bad "$TMP/sc_yaw.json" "$NERAF" synth --scene "$TMP/sc_yaw.json" --dry-run
# F06/F07 --gain-from another room, or an implausible gain.
bad "--gain-from" "$NERAF" synth --preset shoebox --mics random --mic-count 2 \
  --gain-from "$BASE/ss" --out @OUT@ --quiet
fresh ss_gain ss; json_edit "$D/synth_info.json" 'd["gain"] = 1e30'
bad "$D/synth_info.json" "$NERAF" synth --preset demo --mics random --mic-count 2 \
  --gain-from "$D" --out @OUT@ --quiet
D=""
# F10 camera files: a reflection, a position of 1e300 m, a new size without a focal length, a
# principal point off the image.
python3 - "$BASE/run/data.json" "$TMP" <<'PY'
import json, sys
c2w = json.load(open(sys.argv[1]))["eval_camera_to_world"][0]
out = sys.argv[2]
flip = [[-v for v in c2w[0][:3]] + [c2w[0][3]], c2w[1], c2w[2]]
json.dump({"camera_to_world": flip}, open(out + "/cam_reflect.json", "w"))
far = [r[:3] + [1e300 if i == 0 else r[3]] for i, r in enumerate(c2w)]
json.dump({"camera_to_world": far}, open(out + "/cam_far.json", "w"))
json.dump({"camera_to_world": c2w, "intrinsics": {"width": 32, "height": 32}},
          open(out + "/cam_partial.json", "w"))
json.dump({"camera_to_world": c2w, "intrinsics": {"cx": 1e6}}, open(out + "/cam_cx.json", "w"))
PY
for cam in reflect far partial cx; do
  bad "$TMP/cam_$cam.json" "$NERAF" render view --run "$BASE/run" --pose "$TMP/cam_$cam.json" \
    --out @OUT@.png
done
# F12 a number beyond a double, without the JSON library's text.
echo '{"version": 1, "source": [1.1, 1.2, 0.9], "poses": [{"mic": [2, 1.5, 1e400]}]}' \
  >"$TMP/huge_poses.json"
bad "$TMP/huge_poses.json" "$NERAF" render rir --model "$BASE/model.nrf" \
  --poses "$TMP/huge_poses.json" --out @OUT@
grep -q "json.exception" "$TMP/err" && fail "1e400: the JSON library's text: $(cat "$TMP/err")"
# F20 a feature cache among the run's checkpoints.
bad "--cache-dir" "$NERAF" train --data "$BASE/ss" --out "$TMP/cache_run" \
  --cache-dir "$TMP/cache_run/checkpoints" --steps 2 --quiet
bad "--cache-dir" "$NERAF" calibrate --run "$BASE/run" --cache-dir "$BASE/run/checkpoints" --quiet
# F23 flags that do not apply, an empty list entry.
bad "--ablation-runs" "$NERAF" eval --run "$BASE/run" --ablation-runs , --json @OUT@.json \
  --skip-vision --quiet
bad "--seed" "$NERAF" auralize --rir "$WAV" --seed 5 --in "$DRY" --out @OUT@.wav
bad "--max-views" "$NERAF" eval --model "$BASE/model.nrf" --max-views 1 --json @OUT@.json
# F25 a calibration file given as the checkpoint.
calib=$(ls "$BASE/run/checkpoints/"*.calibration.pt | head -n 1)
bad "calibration file" "$NERAF" export --run "$BASE/run" --checkpoint "$calib" --out @OUT@.nrf
# F26 a frame rate named as --fps, a model given as a run, the two path formats swapped, a
# checkpoint renamed by hand.
printf '{"version": 1, "source": [1.1, 1.2, 0.9], "keyframes": [{"time": 0, "mic": [2, 1.5, 2.5], "yaw": 0},
 {"time": 100000, "mic": [2, 1.5, 2.4], "yaw": 0}]}' >"$TMP/long_path.json"
bad "--fps" "$NERAF" render trajectory --run "$BASE/run" --path "$TMP/long_path.json" --in "$DRY" \
  --out @OUT@.wav --frames @OUT@_frames --fps 120
bad "--model" "$NERAF" render rir --run "$BASE/model.nrf" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out @OUT@.wav
echo '{"version": 1, "source": [1.1, 1.2, 0.9], "poses": [{"mic": [2, 1.5, 2.5]}]}' >"$TMP/poses.json"
bad "pose list" "$NERAF" render trajectory --model "$BASE/model.nrf" --path "$TMP/poses.json" \
  --in "$DRY" --out @OUT@.wav
fresh run_hugestep run
for f in "$D"/checkpoints/step-*; do
  case $f in *.calibration.pt) rm "$f" ;; *) mv "$f" "$D/checkpoints/step-99999999999999999999.pt" ;; esac
done
bad "step-99999999999999999999.pt" "$NERAF" render rir --run "$D" --mic 2.0,1.5,2.5 \
  --src 1.1,1.2,0.9 --out @OUT@.wav
D=""
# F21 silence in, silence out: said, not "normalised".
python3 -c "
import struct
open('$TMP/zero.wav','wb').write(b'RIFF'+struct.pack('<I',36+400)+b'WAVEfmt '+struct.pack('<IHHIIHH',16,3,1,22050,88200,4,32)+b'data'+struct.pack('<I',400)+b'\0'*400)"
run "$NERAF" auralize --rir "$TMP/zero.wav" --in "$DRY" --out "$TMP/zero_wet.wav" --normalize
[ "$got" -eq 0 ] && grep -q "every sample of the impulse response is zero" "$TMP/err" &&
  grep -q "silent" "$TMP/out" || fail "auralize of a silent RIR: exit $got, no warning: $(cat "$TMP/err" "$TMP/out")"
# F08 resume after the data changed under the run: a RIR file or a training picture replaced.
fresh ss_resume ss
run "$NERAF" train --data "$D" --out "$TMP/resume_run" --steps 2 --audio-start-step 0 --rays 64 --quiet
[ "$got" -eq 0 ] || fail "train for the resume case: exit $got: $(tail -c 300 "$TMP/err")"
wavs=("$D"/binaural_rirs/0/*.wav)
cp "${wavs[1]}" "${wavs[0]}.new" && mv "${wavs[0]}.new" "${wavs[0]}"
run "$NERAF" train --out "$TMP/resume_run" --resume --steps 3 --quiet
[ "$got" -eq 1 ] && grep -q "^error: .*changed since the run was trained" "$TMP/err" ||
  fail "resume on a changed RIR file: exit $got: $(tail -c 400 "$TMP/err")"
D=""

# --- probe round d (docs/results/fresh_probes_2026-12-04b.md) ---
# G01 a user's files whose names merely hold ".tmp-<digits>" survive the stale-temporary cleanup.
mkdir -p "$TMP/keep"
echo precious >"$TMP/keep/notes.tmp-123456.txt"
cp "$DRY" "$TMP/keep/take.tmp-2024.wav"
mkdir "$TMP/keep/photos.tmp-77777"
run "$NERAF" export --run "$BASE/run" --out "$TMP/keep/m.nrf"
[ "$got" -eq 0 ] && [ -f "$TMP/keep/notes.tmp-123456.txt" ] && [ -f "$TMP/keep/take.tmp-2024.wav" ] &&
  [ -d "$TMP/keep/photos.tmp-77777" ] || fail "export deleted a user's .tmp- files (exit $got)"
echo '{"version": 1, "source": [1.1, 1.2, 0.9], "poses": [{"name": "take.tmp-1", "mic": [2, 1.5, 2.5]}]}' \
  >"$TMP/tmp_name_poses.json"
bad "take.tmp-1" "$NERAF" render rir --model "$BASE/model.nrf" --poses "$TMP/tmp_name_poses.json" \
  --out @OUT@
# G02 an absurd OMP_NUM_THREADS is ignored with a warning, not a crash.
OMP_NUM_THREADS=100000 run "$NERAF" render rir --model "$BASE/model.nrf" --mic 2.0,1.5,2.5 \
  --src 1.1,1.2,0.9 --out "$TMP/omp.wav"
[ "$got" -eq 0 ] && grep -q "^warning: OMP_NUM_THREADS=100000: ignored" "$TMP/err" ||
  fail "OMP_NUM_THREADS=100000: exit $got: $(tail -c 300 "$TMP/err")"
# G03/G19 FIFOs where a file is read: refused at once, not waited on.
mkfifo "$TMP/fifo.nrf" "$TMP/fifo.json" "$TMP/checkpoint_fifo.pt"
bad "$TMP/fifo.nrf" "$NERAF" render rir --model "$TMP/fifo.nrf" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out @OUT@.wav
bad "$TMP/fifo.json" "$NERAF" render trajectory --model "$BASE/model.nrf" --path "$TMP/fifo.json" \
  --in "$DRY" --out @OUT@.wav
bad "not a regular file" "$NERAF" render rir --run "$BASE/run" --checkpoint "$TMP/checkpoint_fifo.pt" \
  --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --out @OUT@.wav
# G05 a file-size limit fails the write with one line and leaves no temporary file.
next_out
(ulimit -f 20; run "$NERAF" render rir --model "$BASE/model.nrf" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out "$O.wav"; echo "$got" >"$TMP/ulimit_rc")
got=$(cat "$TMP/ulimit_rc")
[ "$got" -eq 1 ] && grep -q "^error: " "$TMP/err" || fail "ulimit -f: exit $got: $(tail -c 300 "$TMP/err")"
ls "$TMP" | grep -q "o_$case_no.wav" && fail "ulimit -f: left $(ls "$TMP" | grep "o_$case_no")"
# G16 a flat training box in data.json is a damaged file, not the user's position.
fresh run_flatbox run; json_edit "$D/data.json" 'd["audio"]["aabb_max"] = d["audio"]["aabb_min"]'
bad "$D/data.json" "$NERAF" render rir --run "$D" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --out @OUT@.wav
D=""
# G07 eval after the held-out pictures changed: refused (the run recorded their pixels).
fresh ss_evalpix ss
run "$NERAF" train --data "$D" --out "$TMP/vision_run" --modality vision --steps 2 --rays 64 --quiet
[ "$got" -eq 0 ] || fail "vision train for the eval case: exit $got: $(tail -c 300 "$TMP/err")"
train_pngs=("$D"/images/train_*.png)
eval_pngs=("$D"/images/eval_*.png)
cp "${train_pngs[0]}" "${eval_pngs[0]}"
bad "eval_pixels_fnv1a" "$NERAF" eval --run "$TMP/vision_run" --json @OUT@.json --no-images --quiet
D=""

# probe round d (helper)
# G13 metrics of an RIR shorter than one STFT window (or 50 ms): refused naming the file, not "nan".
float_wav "$TMP/short_rir.wav" 22050 1 0 5
bad "$TMP/short_rir.wav" "$NERAF" metrics --pred "$TMP/short_rir.wav" --gt "$TMP/short_rir.wav"
float_wav "$TMP/long_rir.wav" 22050 1 0.5
run "$NERAF" metrics --pred "$TMP/long_rir.wav" --gt "$TMP/long_rir.wav"
[ "$got" -eq 0 ] || fail "metrics of a 2000-sample RIR exited $got: $(tail -c 300 "$TMP/err")"
# G09 camera files with a focal length of 1e-320 px or a k1 of 1e308.
python3 - "$BASE/run/data.json" "$TMP" <<'PY'
import json, sys
c2w = json.load(open(sys.argv[1]))["eval_camera_to_world"][0]
json.dump({"camera_to_world": c2w, "intrinsics": {"fx": 1e-320, "fy": 1e-320}},
          open(sys.argv[2] + "/cam_fxsub.json", "w"))
json.dump({"camera_to_world": c2w, "intrinsics": {"k1": 1e308}},
          open(sys.argv[2] + "/cam_k1big.json", "w"))
PY
bad "fx is" "$NERAF" render view --run "$BASE/run" --pose "$TMP/cam_fxsub.json" --out @OUT@.png
bad "k1 is" "$NERAF" render view --run "$BASE/run" --pose "$TMP/cam_k1big.json" --out @OUT@.png
# G18 a NUL in data.json's dataset path (the folder before it was read).
fresh run_datanul run; json_edit "$D/data.json" 'd["data"] = d["data"] + "\u0000junk"'
bad "$D/data.json" "$NERAF" render rir --run "$D" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 --out @OUT@.wav
D=""
# G17 a scene light of 1e308 or a texture cell of 1e-320 m.
cp "$TMP/demo_scene.json" "$TMP/sc_light.json"; json_edit "$TMP/sc_light.json" 'd["light"]["intensity"] = 1e308'
bad "light.intensity" "$NERAF" synth --scene "$TMP/sc_light.json" --dry-run
cp "$TMP/demo_scene.json" "$TMP/sc_tex.json"; json_edit "$TMP/sc_tex.json" 'd["materials"]["wall"]["texture"]["scale_m"] = 1e-320'
bad "texture.scale_m" "$NERAF" synth --scene "$TMP/sc_tex.json" --dry-run
# G08 a model whose header was edited behind a recomputed checksum.
python3 - "$BASE/model.nrf" "$TMP/oscale.nrf" <<'PY'
import json, struct, sys
b = open(sys.argv[1], "rb").read()
payload = b[24:-8]
n = struct.unpack("<Q", payload[:8])[0]
h = json.loads(payload[8:8 + n])
h["output_scale"] = 1e308
t = json.dumps(h).encode()
payload = struct.pack("<Q", len(t)) + t + payload[8 + n:]
fnv = 0xcbf29ce484222325
for c in payload:
    fnv = ((fnv ^ c) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
open(sys.argv[2], "wb").write(b[:16] + struct.pack("<Q", len(payload)) + payload + struct.pack("<Q", fnv))
PY
bad "output_scale" "$NERAF" render rir --model "$TMP/oscale.nrf" --mic 2.0,1.5,2.5 --src 1.1,1.2,0.9 \
  --out @OUT@.wav

# P23 info takes the transforms.json form as train does.
run "$NERAF" info --no-t60 "$BASE/ss/transforms.json"
[ "$got" -eq 0 ] || fail "info DS/transforms.json exited $got: $(tail -c 300 "$TMP/err")"

# A mistyped command or option gets a suggestion.
run "$NERAF" trian --data x
[ "$got" -eq 2 ] && grep -q "did you mean 'train'" "$TMP/err" ||
  fail "neraf trian: exit $got, no suggestion: $(head -c 300 "$TMP/err")"
run "$NERAF" train --data x --out y --stpes 3
[ "$got" -eq 2 ] && grep -q "did you mean '--steps'" "$TMP/err" ||
  fail "train --stpes: exit $got, no suggestion: $(head -c 300 "$TMP/err")"

run "$NERAF" info "$BASE/ss" --json
[ "$got" -eq 0 ] || fail "info --json on a good set exited $got"
timeout 60 "$NERAF" info "$BASE/ss" --json >/dev/full 2>"$TMP/err"
[ $? -eq 1 ] && grep -q "^error: cannot write to standard output" "$TMP/err" ||
  fail "info --json > /dev/full did not fail: $(cat "$TMP/err")"

[ "$classes" -ge 30 ] || fail "only $classes classes of bad input"
echo "$classes classes of bad input"
finish bad_input
