#!/usr/bin/env bash
# Minor UNCLEAR / SILENT cases P21-P29.
source "$(dirname "$0")/setup.sh"
echo "== P21"; $N train --data ds --out m21 --steps 2 --audio-start-step 100 --quiet
echo "== P22"; $N launch -n 2 train --data ds --out m22 --steps 1 --quiet 2>&1 | head -1
echo "== P23"; $N info ds/transforms.json 2>&1 | head -1
echo "== P24"; mkdir -p fr; echo x > fr/notes.txt; touch fr/frame_00099.png
  $N render trajectory --run run --path path.json --in dry.wav --frames fr --out fr.wav 2>/dev/null; echo "rc=$?"; ls fr | tail -3
echo "== P25"; $N eval --run run --json e25.json --images run/checkpoints --max-views 1 --no-baselines --quiet; echo "rc=$?"; ls run/checkpoints; rm -f run/checkpoints/*.png run/checkpoints/*.csv
echo "== P26"; $N render rir --run run $MIC --out -; echo "rc=$?"; ls -la -- -; rm -f -- -
echo "== P27"; echo '{"version":1,"source":[1.5,1.2,1.3],"keyframes":[{"time":1000,"mic":[1.5,1.5,1.5],"yaw":0},{"time":1001,"mic":[1,1.5,1],"yaw":0}]}' > late.json
  $N render trajectory --model model.nrf --path late.json --in dry.wav --out late.wav 2>&1 | grep -v "render trajectory"; echo "rc=${PIPESTATUS[0]}"
echo "== P28"; $N train --resume --out run --steps 1 --quiet; echo "rc=$?"
echo "== P29"; $N render rir --model model.nrf --mic 1e300,1.5,1.5 --src 1.5,1.2,1.3 --allow-outside --out far.wav 2>&1 | head -c 200; echo
