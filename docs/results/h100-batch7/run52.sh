#!/bin/bash
# GPU batch 52 (issue 28 on one H100, no two-GPU machine lent): what
# --row-order spread does to the pieces two GPUs would take.
#  A. one GPU, no pieces: 934e96d (.gpu/rtcl-base) against the row map's
#     commit (.gpu/rtcl), interleaved: the map must cost nothing.
#  B. the image in two (and four) pieces on one GPU (--devices P:0
#     --piece-rows), scan against spread: each piece's kernel time, which is
#     what each of two GPUs would spend on its half.
#  C. GPU + the machine's CPU (PoCL), before and after, both orders.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu
echo "commit: $COMMIT"; nvidia-smi -L
$G/rtcl --list-devices
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($G/rtcl --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
ms() { grep -o '"kernel_ms": [0-9.]*' $1 | head -1 | awk '{print $2}'; }
pieces() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d['multidevice']
ps = md['pieces']; k = [p['kernel_ms'] for p in ps]
print('    %s: image %.1f ms; pieces (split rows: kernel ms) %s; sum %.1f, max/mean %.3f' % (
    md['row_order'], d['kernel_ms'], ', '.join('%d-%d: %.1f' % (p['y0'], p['y0'] + p['height'] - 1,
    p['kernel_ms']) for p in ps), sum(k), max(k) / (sum(k) / len(k))))" $1; }
echo "== A. one GPU, no pieces (median kernel ms)"
for round in 1 2 3; do
  for b in rtcl-base rtcl; do
    $G/$b -p $P -k persistent -w 8x8 --size 2000x2000 -r 20 -q -o $T/a-$b.ppm --stats $T/s.json
    echo "  round $round default persistent $b $(ms $T/s.json)"
    $G/$b -p $P -k dynamic --size 2000x2000 --spp 1024 -r 3 -q -o $T/b-$b.ppm --stats $T/s.json
    echo "  round $round default spp1024 dynamic $b $(ms $T/s.json)"
  done
done
cmp $T/a-rtcl-base.ppm $T/a-rtcl.ppm && cmp $T/b-rtcl-base.ppm $T/b-rtcl.ppm && echo "  images identical"
echo "== B. pieces on one GPU (-r 3, last frame's pieces)"
declare -A S=([default]="--size 2000x2000 --spp 1024" [lake]="-s $T/lake/lake-10.json --size 2000x2000 --spp 256")
for s in default lake; do
  $G/rtcl -p $P -k dynamic ${S[$s]} -r 3 -q -o $T/one-$s.ppm --stats $T/s.json
  echo "  $s whole image, one launch series: $(ms $T/s.json) ms"
  for rows in 1000 500; do
    for order in scan spread; do
      $G/rtcl --devices $P:0 -k dynamic ${S[$s]} -r 3 --piece-rows $rows --row-order $order -q \
        -o $T/p-$s.ppm --stats $T/s.json
      echo "  $s --piece-rows $rows:"; pieces $T/s.json
      cmp -s $T/one-$s.ppm $T/p-$s.ppm || echo "    IMAGE DIFFERS"
    done
  done
done
echo "== C. GPU + CPU, default scene spp 1024 (-r 3)"
for round in 1 2; do
  for v in "rtcl-base" "rtcl --row-order scan" "rtcl --row-order spread"; do
    set -- $v
    $G/$1 --devices $P:0,$C:0 -k dynamic --size 2000x2000 --spp 1024 -r 3 ${2:-} ${3:-} -q \
      -o $T/c.ppm --stats $T/s.json
    echo "  round $round $v: $(ms $T/s.json) ms; $(python3 -c "
import json, sys; md = json.load(open(sys.argv[1]))['multidevice']
print(', '.join('%s %d pieces %d px busy %.0f' % (d['device'][:12], d['pieces'], d['pixels'], d['busy_ms']) for d in md['devices']), 'eff %.3f' % md['device_efficiency'])" $T/s.json)"
  done
done
