#!/usr/bin/env bash
# P20 UNCLEAR: an unreadable audio file is "not an audio file libsndfile can read (... Permission denied.)".
source "$(dirname "$0")/setup.sh"
cp dry.wav ro.wav; chmod 000 ro.wav; chmod 755 "$W"; mkdir -p nob; chmod 777 nob
runuser -u nobody -- "$NERAF" auralize --rir ds/binaural_rirs/0/0_9.wav --in ro.wav --out nob/o.wav; echo "rc=$?"
