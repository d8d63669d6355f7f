#!/usr/bin/env bash
# P07 SILENT: duplicate keys accepted in path / pose JSON and transforms.json (scene.json refuses them).
source "$(dirname "$0")/setup.sh"
echo '{"version":1,"source":[1.5,1.2,1.3],"source":[2.5,1.2,2.3],"poses":[{"mic":[1.5,1.5,1.5],"yaw":0,"mic":[1,1.5,1]}]}' > dup_poses.json
rm -rf dupP; $N render rir --model model.nrf --poses dup_poses.json --out dupP; echo "rc=$?"; cat dupP/summary.csv
echo '{"version": 1, "source":[1.5,1.2,1.3],"keyframes":[{"time":0,"mic":[1.5,1.5,1.5],"yaw":0,"yaw":90}]}' > dup_path.json
$N render trajectory --model model.nrf --path dup_path.json --in dry.wav --out dup.wav 2>/dev/null; echo "rc=$?"
rm -rf tfdup; cp -r ds tfdup; sed -i '0,/{/s//{"fl_x": 999, /' tfdup/transforms.json
$N info tfdup --no-t60 | tail -1
