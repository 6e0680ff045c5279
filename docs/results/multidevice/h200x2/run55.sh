#!/bin/bash
# Issue 28's measurement, ready for the first two-GPU machine lent
# (nvidia-h200-x2; not lent when this was written, 2026-11-25): one image
# over two GPUs against one, median of 3 whole renders (-r 3 times the whole
# multi-device image after a warm-up), both row orders, the default scene at
# 1024 spp and the lake (2.1 M triangles) at 256 spp, 2000x2000, dynamic.
# Run: COMMIT=<commit> bash docs/results/multidevice/h200x2/run55.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
$R --list-devices
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
declare -A S=([default]="--size 2000x2000 --spp 1024" [lake]="-s $T/lake/lake-10.json --size 2000x2000 --spp 256")
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'median %.1f ms (min %.1f, max %.1f)' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'])
if md:
    line += '; ' + ', '.join('dev %d: %d pieces, busy %.1f, kernels %.1f' % (k, x['pieces'], x['busy_ms'],
        x['kernel_ms']) for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f; %s' % (md['device_efficiency'], md['row_order'])
print(line)" $1; }
for s in default lake; do
  for round in 1 2; do
    $R -p $P -d 0 -k dynamic ${S[$s]} -r 3 -q -o $T/one-$s.ppm --stats $T/s.json
    echo "$s round $round one GPU: $(show $T/s.json)"
    for o in interleave scan; do
      $R --devices $P:0,$P:1 --row-order $o -k dynamic ${S[$s]} -r 3 -q -o $T/two-$s-$o.ppm \
        --stats $T/s.json
      echo "$s round $round two GPUs, $o: $(show $T/s.json)"
      cmp -s $T/one-$s.ppm $T/two-$s-$o.ppm && echo "  image identical to one GPU's" \
        || echo "  IMAGE DIFFERS"
    done
  done
  for i in 1 2; do
    TIMEFORMAT="$s one GPU, whole process: %R s"; time $R -p $P -d 0 -k dynamic ${S[$s]} -q -o $T/w.png
    TIMEFORMAT="$s two GPUs, whole process: %R s"; time $R --devices $P:0,$P:1 -k dynamic ${S[$s]} -q -o $T/w.png
  done
done
