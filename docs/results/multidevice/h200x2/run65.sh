#!/bin/bash
# Issue 28, batch 65 (two H200s): with queues hiding the launches' ends,
# do larger passes pay (RTCL_X_PASS_SAMPLES, run64-experiment.patch: the
# default is about 2^22 pixel-samples a pass, 1 sample of the whole image,
# 2 of a GPU's half)? And the adaptive split's rate-weighted floor
# (bdee288): the faster GPU takes more than its half. Binary: bdee288 with
# the patch. -r 3 medians, rounds interleaved.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run65.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl
T=$(mktemp -d); O=$T/json65; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'kernels %.1f ms (min %.1f, max %.1f), wall %.1f, %d queues, %d passes' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), d.get('queues', 0), d.get('passes', 0))
if md:
    line += '; ' + ', '.join('dev %d: %d pieces, %d px, busy %.1f, kernels %.1f in %d launches' % (k,
        x['pieces'], x['pixels'], x['busy_ms'], x['kernel_ms'], x['launches'])
        for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f' % md['device_efficiency']
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm  # fills the program cache
$R -p $P -d 0 $L --size 64x64 -q -o $T/prime.ppm
$R -p $P -d 0 $D --queues 1 -q -o $T/ref.ppm
one() { # tag, pass samples, args...
  local tag=$1 p=$2; shift 2
  RTCL_X_PASS_SAMPLES=$p $R "$@" -r 3 -q -o $T/x.ppm --stats $O/$tag.json
  echo "$tag (pass ${p:-default}): $(show $O/$tag.json)"; same $T/ref.ppm $T/x.ppm; }
for round in 1 2; do
  for p in "" 2 4; do one d1-q2-p$p-$round "$p" -p $P -d 0 $D --queues 2; done
  for p in "" 4 8; do one d2-q2-p$p-$round "$p" --devices $P:0,$P:1 $D --queues 2; done
  for p in "" 4; do one d2-q4-p$p-$round "$p" --devices $P:0,$P:1 $D --queues 4; done
done
$R -p $P -d 0 $L --queues 1 -q -o $T/ref.ppm
for p in "" 2 4; do one l1-q2-p$p "$p" -p $P -d 0 $L --queues 2; done
for p in "" 4; do one l2-q2-p$p "$p" --devices $P:0,$P:1 $L --queues 2; done
one l2-q4 "" --devices $P:0,$P:1 $L --queues 4
tar czf $OUT/batch65-json.tgz -C $T json65
