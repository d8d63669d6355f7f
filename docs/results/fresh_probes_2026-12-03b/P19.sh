#!/usr/bin/env bash
# P19 UNCLEAR: the resampling error names neither the file nor --in.
source "$(dirname "$0")/setup.sh"
python3 -c "
import struct; n=20; d=struct.pack('<%dh'%n,*([1000]*n))
open('dry_1hz.wav','wb').write(b'RIFF'+struct.pack('<I',36+len(d))+b'WAVEfmt '+struct.pack('<IHHIIHH',16,1,1,1,2,2,16)+b'data'+struct.pack('<I',len(d))+d)"
$N auralize --rir ds/binaural_rirs/0/0_9.wav --in dry_1hz.wav --out o.wav 2>&1 | grep error; echo "rc=${PIPESTATUS[0]}"
