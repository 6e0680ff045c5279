#!/bin/bash
# GPU batch 53 (issue 28 on one H100): the three row orders' pieces. Batch
# 52 found spread pieces balanced (max/mean 1.05 for two halves) but slower
# in sum than contiguous ones. Here: the image in 1, 2 and 4 pieces on one
# GPU (--devices P:0 --piece-rows), in scan, spread and interleave:N order
# (N the pieces), each piece's kernel time; what each of N GPUs would spend.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
pieces() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d['multidevice']
ps = md['pieces']; k = [p['kernel_ms'] for p in ps]
print('    %-13s image %7.1f ms; pieces %s; sum %.1f, max %.1f, max/mean %.3f' % (sys.argv[2],
    d['kernel_ms'], ' '.join('%.1f' % x for x in k), sum(k), max(k), max(k) / (sum(k) / len(k))))" $1 $2; }
declare -A S=([default]="--size 2000x2000 --spp 1024" [lake]="-s $T/lake/lake-10.json --size 2000x2000 --spp 256")
for k in dynamic persistent; do
for s in default lake; do
  $G/rtcl -p $P -k $k -w 8x8 ${S[$s]} -r 3 -q -o $T/one-$s.ppm --stats $T/s.json
  echo "== $s -k $k: whole image, plain render $(grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1 | awk '{print $2}') ms"
  for n in 1 2 4; do
    echo "  $n piece(s) of $((2000 / n)) rows:"
    for order in scan spread interleave:$n; do
      [ $n = 1 ] && [ $order = interleave:1 ] && order=interleave:2
      $G/rtcl --devices $P:0 -k $k -w 8x8 ${S[$s]} -r 3 --piece-rows $((2000 / n)) --row-order $order -q \
        -o $T/p.ppm --stats $T/s.json
      pieces $T/s.json $order
      cmp -s $T/one-$s.ppm $T/p.ppm || echo "    IMAGE DIFFERS"
    done
  done
done
done
