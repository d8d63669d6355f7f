#!/usr/bin/env bash
# P15 BADFLAG/UNCLEAR: launch -n 3 cannot work (audio batch 512, --rays) and the errors name flags the
# user did not give / may not give (--world-size is refused by launch); the thread warning advises
# --threads 1, which each rank already has. Starts 3 processes briefly.
source "$(dirname "$0")/setup.sh"
rm -rf L12 L13
$N launch -n 3 -- train --data ds --out L12 --steps 1 --quiet; echo "rc=$?"
$N launch -n 3 -- train --data ds --out L13 --steps 1 --rays 129 --threads 1 --quiet; echo "rc=$?"
$N launch -n 3 -- train --data ds --out L13 --world-size 3 --steps 1 --quiet; echo "rc=$?"
