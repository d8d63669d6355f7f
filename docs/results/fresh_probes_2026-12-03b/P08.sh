#!/usr/bin/env bash
# P08 SILENT: render view --pose ignores misspelled keys and truncates a fractional width.
source "$(dirname "$0")/setup.sh"
python3 -c "
import json; c=json.load(open('run/data.json'))['eval_camera_to_world'][0]
json.dump({'camera_to_world':c,'intrinsics':{'widht':32,'heigth':32}}, open('p1.json','w'))
json.dump({'camera_to_world':c,'intrinsic':{'width':32,'height':32}}, open('p2.json','w'))
json.dump({'camera_to_world':c,'intrinsics':{'width':16.5,'height':16}}, open('p3.json','w'))"
for p in p1 p2 p3; do $N render view --run run --pose $p.json --out $p.png; echo "rc=$?"; file $p.png; done
