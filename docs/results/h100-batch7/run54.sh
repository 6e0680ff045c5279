#!/bin/bash
# GPU batch 54 (issue 28 on one H100): interleave (ac2a0bd, .gpu/rtcl) in
# three interleaved rounds against 934e96d (.gpu/rtcl-base), since the
# H100's clock drifts over a batch (batch 52: the same render took 865 ms
# first and 924-929 ms later):
#  - one GPU, plain: the row map costs nothing when nothing is split;
#  - the image in two halves on one GPU (--devices P:0 --piece-rows 1000),
#    interleave:2 against scan: each half's kernel time is what each of two
#    GPUs would spend; predicted two-GPU speed-up = plain / slower half;
#  - GPU + the machine's CPU: one GPU, so one class (scan), as before.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($G/rtcl --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
ms() { grep -o '"kernel_ms": [0-9.]*' $1 | head -1 | awk '{print $2}'; }
halves() { python3 -c "
import json, sys
md = json.load(open(sys.argv[1]))['multidevice']; k = [p['kernel_ms'] for p in md['pieces']]
print('%s %s sum %.1f' % (md['row_order'], ' '.join('%.1f' % x for x in k), sum(k)))" $1; }
declare -A S=([default]="--size 2000x2000 --spp 1024" [lake]="-s $T/lake/lake-10.json --size 2000x2000 --spp 256")
for round in 1 2 3; do
  for s in default lake; do
    for b in rtcl-base rtcl; do
      $G/$b -p $P -k dynamic -w 8x8 ${S[$s]} -r 3 -q -o $T/one-$s-$b.ppm --stats $T/s.json
      echo "round $round $s plain $b $(ms $T/s.json)"
    done
    for o in interleave:2 scan; do
      $G/rtcl --devices $P:0 -k dynamic -w 8x8 ${S[$s]} -r 3 --piece-rows 1000 --row-order $o -q \
        -o $T/h.ppm --stats $T/s.json
      echo "round $round $s halves $(halves $T/s.json)"
      cmp -s $T/h.ppm $T/one-$s-rtcl.ppm || echo "  IMAGE DIFFERS"
    done
  done
  for b in rtcl-base rtcl; do
    $G/$b --devices $P:0,$C:0 -k dynamic --size 2000x2000 --spp 1024 -r 3 -q -o $T/c.ppm --stats $T/s.json
    echo "round $round gpu+cpu $b $(ms $T/s.json) $(python3 -c "
import json, sys; md = json.load(open(sys.argv[1]))['multidevice']
print(' '.join('%d/%d' % (d['pieces'], d['pixels']) for d in md['devices']), md.get('row_order', '-'))" $T/s.json)"
  done
  for b in rtcl-base rtcl; do
    $G/$b -p $P -k persistent -w 8x8 --size 2000x2000 -r 20 -q -o $T/p-$b.ppm --stats $T/s.json
    echo "round $round primary persistent $b $(ms $T/s.json)"
  done
done
for s in default lake; do cmp -s $T/one-$s-rtcl-base.ppm $T/one-$s-rtcl.ppm && echo "$s: images identical"; done
