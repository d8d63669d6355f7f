#!/usr/bin/env bash
# Drives the `neraf` program as a user would: exit codes, --help, one-line errors, JSON outputs.
# Usage: cli_smoke.sh <path to neraf> <assets dir>
set -u
NERAF=$1
ASSETS=$2
source "$(dirname "$0")/lib.sh"

# --- the program and its help -------------------------------------------------------------
expect_exit 0 "$NERAF" --help
for cmd in metrics auralize synth info train eval render; do expect_in "$TMP/out" "$cmd"; done
expect_exit 0 "$NERAF" --version
expect_in "$TMP/out" "LibTorch"
expect_in "$TMP/out" "openblas"
# libgomp's idle threads spin 1,000 turns, not its 300,000 (two processes on the same cores would
# hold each other's), unless the user chose how they wait.
expect_exit 0 env -u GOMP_SPINCOUNT -u OMP_WAIT_POLICY "$NERAF" --version
expect_in "$TMP/out" "OpenMP wait GOMP_SPINCOUNT=1000"
expect_exit 0 env -u GOMP_SPINCOUNT OMP_WAIT_POLICY=PASSIVE "$NERAF" --version
expect_in "$TMP/out" "OpenMP wait OMP_WAIT_POLICY=PASSIVE"
grep -q GOMP_SPINCOUNT "$TMP/out" && fail "neraf set GOMP_SPINCOUNT beside the user's OMP_WAIT_POLICY"
# Run again under its own name: ps, top and pkill still see the binary's name, not "exe".
env -u GOMP_SPINCOUNT -u OMP_WAIT_POLICY "$NERAF" synth --preset demo --out "$TMP/comm" --quiet \
  >/dev/null 2>&1 &
pid=$!
for _ in $(seq 300); do  # until the second start (its environment has the setting)
  tr '\0' '\n' <"/proc/$pid/environ" 2>/dev/null | grep -qx GOMP_SPINCOUNT=1000 && break
  sleep 0.1
done
comm=$(cat "/proc/$pid/comm" 2>/dev/null)
kill "$pid" 2>/dev/null
wait "$pid" 2>/dev/null
[ "$comm" = "$(basename "$NERAF" | cut -c1-15)" ] || fail "neraf runs as '$comm' after its start-up re-run"
expect_exit 2 "$NERAF"
expect_exit 2 "$NERAF" no-such-command
expect_exit 2 "$NERAF" metrics --no-such-flag
expect_in "$TMP/err" "Usage"
for cmd in metrics auralize synth info train eval render; do
  expect_exit 0 "$NERAF" "$cmd" --help
  expect_in "$TMP/out" "Usage"
done

# --- metrics ------------------------------------------------------------------------------
expect_exit 0 "$NERAF" metrics --rir "$ASSETS/real/rir_clap.wav" --json
expect_in "$TMP/out" '"t60"'
python3 - "$TMP/out" <<'PY' || fail "metrics --json output"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["fs"] == 44100, d
ch = d["channels"][0]
assert abs(ch["t60"] - 0.913878) < 1e-3 and abs(ch["edt"] - 0.526939) < 1e-3, ch
assert abs(ch["c50"] - 4.976388) < 1e-2, ch
PY
expect_exit 0 "$NERAF" metrics --pred "$ASSETS/real/brir_clap.wav" --gt "$ASSETS/real/brir_clap.wav" --json
python3 - "$TMP/out" <<'PY' || fail "metrics pred==gt errors are zero"
import json, sys
d = json.load(open(sys.argv[1]))
for k in ("t60_error_pct", "c50_error_db", "edt_error_s", "stft_error", "invalid_t60"):
    assert k in d, k
assert d["t60_error_pct"] == 0 and d["c50_error_db"] == 0 and d["edt_error_s"] == 0, d
PY
expect_exit 1 "$NERAF" metrics --rir "$TMP/missing.wav"
expect_in "$TMP/err" "missing.wav"
[ "$(wc -l <"$TMP/err")" -eq 1 ] || fail "runtime error should be one line: $(cat "$TMP/err")"
echo "not audio" >"$TMP/text.wav"
expect_exit 1 "$NERAF" metrics --rir "$TMP/text.wav"
expect_in "$TMP/err" "text.wav"
: >"$TMP/empty.wav"
expect_exit 1 "$NERAF" metrics --rir "$TMP/empty.wav"
expect_exit 1 "$NERAF" metrics --pred "$ASSETS/real/rir_clap.wav" --gt "$ASSETS/real/brir_clap.wav"
expect_in "$TMP/err" "channel"

# --- auralize -----------------------------------------------------------------------------
expect_exit 0 "$NERAF" auralize --rir "$ASSETS/real/brir_clap.wav" --in "$ASSETS/real/castanets_dry.wav" \
  --out "$TMP/wet.wav" --normalize
[ -f "$TMP/wet.wav" ] || fail "auralize wrote no file"
ls "$TMP" | grep -q 'tmp-' && fail "auralize left a temporary file"
expect_exit 1 "$NERAF" auralize --rir "$TMP/missing.wav" --in "$ASSETS/real/castanets_dry.wav" --out "$TMP/x.wav"
[ -f "$TMP/x.wav" ] && fail "failed auralize left an output"

finish "CLI"
