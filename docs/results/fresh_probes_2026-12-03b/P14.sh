#!/usr/bin/env bash
# P14 UNCLEAR: a damaged data.json "audio" section is not range-checked; errors blame other things.
source "$(dirname "$0")/setup.sh"
for edit in 'a["hop_length"]=0' 'a["sample_rate"]=0' 'a["max_len"]=0' 'a["n_fft"]=7' 'a["aabb_min"]=[5,5,5]'; do
  rm -rf dm; mkdir dm; cp run/config.json run/data.json dm/; ln -s "$W/run/checkpoints" dm/checkpoints
  python3 -c "
import json; m=json.load(open('dm/data.json')); a=m['audio']; $edit; json.dump(m,open('dm/data.json','w'))"
  echo "== $edit"; $N render rir --run dm $MIC --out dm.wav; echo "rc=$?"
done
