#!/bin/bash
# Issue 43, batch 97 (four H100s): --frames with each frame staged in a
# thread of its own while the device renders the next, against c6cf709
# (.gpu/rtcl-c6c, frames staged in the device's thread, as batch 95), two
# interleaved rounds: 16 frames of the default scene's orbit at 256 spp,
# 2000x2000, PPM, on 1, 2 and 4 GPUs, and 6 frames on 4; every frame of
# the new binary compared with the old one's on one GPU.
#   COMMIT=<commit> bash .gpu/run97.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; T=$(mktemp -d); O=$T/b97; mkdir -p $O
echo "commit: $COMMIT (old: c6cf709)"; nvidia-smi -L; date -u
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ONE="-p $P -d 0"; TWO="--devices $P:0,$P:1"; FOUR="--devices $P:0,$P:1,$P:2,$P:3"
F="-k dynamic --size 2000x2000 --spp 256"
for b in rtcl rtcl-c6c; do $G/$b $ONE $F --spp 4 -q -o $T/prime.ppm; done
fr() { # tag, binary, devices, last frame
  mkdir -p $T/$1
  $G/$2 ${!3} $F --frames 0:$4 -q -o $T/$1/f.ppm --stats $O/$1.json 2>&1 | head -3
  python3 -c "import json; d=json.load(open('$O/$1.json')); md=d.get('multidevice') or {}
print('$1: wall %.1f ms;' % d['wall_ms'], '; '.join('%d frames busy %.1f kern %.1f fin %.1f' % (x['pieces'], x['busy_ms'], x['kernel_ms'], x['finish_ms']) for x in md.get('devices', [])), '; eff %.3f' % md.get('device_efficiency', 1))" 2>&1; }
for round in 1 2; do
  for b in rtcl-c6c rtcl; do
    for n in ONE TWO FOUR; do fr $b-$n-$round $b $n 15; done
    fr $b-six-$round $b FOUR 5
  done
done
for k in 0000 0007 0015; do
  for x in rtcl-ONE-1 rtcl-FOUR-1 rtcl-FOUR-2 rtcl-c6c-FOUR-1; do
    cmp -s $T/rtcl-c6c-ONE-1/f_$k.ppm $T/$x/f_$k.ppm && echo "  $x f_$k same bytes" || echo "  $x f_$k DIFFERS"
  done
done
tar czf $OUT/batch97-json.tgz -C $T b97; date -u
