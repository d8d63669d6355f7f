#!/usr/bin/env bash
# P13 CRASH (raw libtorch text): config.json is not validated by render/eval (only by train).
source "$(dirname "$0")/setup.sh"
rm -rf chunk0; mkdir chunk0; cp run/config.json run/data.json chunk0/; ln -s "$W/run/checkpoints" chunk0/checkpoints
python3 -c "
import json; c=json.load(open('chunk0/config.json')); c['eval_rays_per_chunk']=0; json.dump(c,open('chunk0/config.json','w'))"
$N render view --run chunk0 --frame 0 --out v.png; echo "rc=$?"
