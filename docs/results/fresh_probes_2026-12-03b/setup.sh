#!/usr/bin/env bash
# Shared fixtures for the repro scripts: a 9-position tiny room, a 2-step run, its model.
# Usage: source setup.sh   (sets N, W; builds W/ds, W/run, W/model.nrf, W/dry.wav once)
set -u
NERAF=${NERAF:-$PWD/build/neraf}  # run from the repository root, or set NERAF
N="nice -n 19 timeout 120 $NERAF"
W=${W:-/tmp/neraf-probes-2026-12-03b}
mkdir -p "$W"; cd "$W"
if [ ! -f tiny.json ]; then cat > tiny.json <<'J'
{"name": "tiny", "size": [3, 2.5, 3],
 "microphones": {"grid": {"spacing_m": 1.0, "wall_margin_m": 0.5, "headings_deg": [0, 180]}},
 "sources": [{"position": [1.5, 1.2, 1.3]}],
 "cameras": {"train_count": 4, "eval_count": 2, "width": 16, "height": 16, "supersampling": 1},
 "acoustics": {"max_order": 2, "rir_length_s": 0.2}}
J
fi
[ -d ds ] || $N synth --scene tiny.json --out ds --quiet >/dev/null
[ -d run ] || $N train --data ds --out run --steps 2 --audio-start-step 0 --rays 128 --quiet >/dev/null 2>&1
[ -f model.nrf ] || $N export --run run --out model.nrf >/dev/null 2>&1
[ -f dry.wav ] || python3 - <<'P'
import struct, math
n=11025; d=struct.pack("<%df"%n,*[0.3*math.sin(i*0.05) for i in range(n)])
open("dry.wav","wb").write(b"RIFF"+struct.pack("<I",36+len(d))+b"WAVEfmt "+struct.pack("<IHHIIHH",16,3,1,22050,22050*4,4,32)+b"data"+struct.pack("<I",len(d))+d)
P
[ -f path.json ] || echo '{"version": 1, "source": [1.5, 1.2, 1.3], "keyframes": [{"time": 0, "mic": [0.5,1.5,0.5], "yaw": 0}, {"time": 0.5, "mic": [2.5,1.5,2.5], "yaw": 180}]}' > path.json
MIC="--mic 1.5,1.5,1.5 --src 1.5,1.2,1.3"
