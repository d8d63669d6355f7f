#!/usr/bin/env bash
# P17 UNCLEAR: a checkpoint that is a folder / device, or checkpoints/ being a file: "no checkpoint yet; train first".
source "$(dirname "$0")/setup.sh"
for k in dir dev file; do
  rm -rf ck$k; mkdir -p ck$k/checkpoints; cp run/config.json run/data.json ck$k/
  case $k in dir) mkdir ck$k/checkpoints/step-000000002.pt;; dev) ln -s /dev/zero ck$k/checkpoints/step-000000002.pt;;
             file) rm -rf ck$k/checkpoints; echo x > ck$k/checkpoints;; esac
  $N render rir --run ck$k $MIC --out ck.wav; echo "rc=$?"
done
$N train --resume --out ckdir --steps 2 --quiet; echo "resume rc=$? (trained, then failed at the save)"
