#!/bin/bash
# Issue 28, batch 64 (two H200s): how many queues (2, 3, 4), and passes of
# one sample (RTCL_X_PASS_SAMPLES, run64-experiment.patch: a GPU's half of
# the image otherwise takes 2 samples a pass) now that queues overlap the
# launches' ends. Binary: commit 5b8ed24 with the patch. Default scene
# 2000x2000 2048 spp and the lake at 256 spp, kernel dynamic, -r 3 medians,
# rounds interleaved; one GPU's figure is its wall time per frame (frame_ms).
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run64.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json64; mkdir -p $O
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
$R -p $P -d 0 $D --queues 1 -r 3 -q -o $T/ref.ppm --stats $O/d1-q1.json
echo "default one GPU: $(show $O/d1-q1.json)"
for round in 1 2; do
  for q in 2 3 4; do
    $R -p $P -d 0 $D --queues $q -r 3 -q -o $T/x.ppm --stats $O/d1-q$q-$round.json
    echo "default one GPU, round $round: $(show $O/d1-q$q-$round.json)"; same $T/ref.ppm $T/x.ppm
    $R --devices $P:0,$P:1 $D --queues $q -r 3 -q -o $T/x.ppm --stats $O/d2-q$q-$round.json
    echo "default two GPUs, round $round: $(show $O/d2-q$q-$round.json)"; same $T/ref.ppm $T/x.ppm
  done
  for q in 2 3; do
    RTCL_X_PASS_SAMPLES=1 $R --devices $P:0,$P:1 $D --queues $q -r 3 -q -o $T/x.ppm --stats $O/d2-q$q-p1-$round.json
    echo "default two GPUs, passes of 1 sample, round $round: $(show $O/d2-q$q-p1-$round.json)"; same $T/ref.ppm $T/x.ppm
  done
done
$R -p $P -d 0 $L --queues 1 -r 3 -q -o $T/lref.ppm --stats $O/l1-q1.json
echo "lake one GPU: $(show $O/l1-q1.json)"
for q in 2 3; do
  $R -p $P -d 0 $L --queues $q -r 3 -q -o $T/x.ppm --stats $O/l1-q$q.json
  echo "lake one GPU: $(show $O/l1-q$q.json)"; same $T/lref.ppm $T/x.ppm
  $R --devices $P:0,$P:1 $L --queues $q -r 3 -q -o $T/x.ppm --stats $O/l2-q$q.json
  echo "lake two GPUs: $(show $O/l2-q$q.json)"; same $T/lref.ppm $T/x.ppm
done
RTCL_X_PASS_SAMPLES=1 $R --devices $P:0,$P:1 $L --queues 2 -r 3 -q -o $T/x.ppm --stats $O/l2-q2-p1.json
echo "lake two GPUs, passes of 1 sample: $(show $O/l2-q2-p1.json)"; same $T/lref.ppm $T/x.ppm
tar czf $OUT/batch64-json.tgz -C $T json64
