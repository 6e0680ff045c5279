#!/bin/bash
# GPU batch 93 (issue 26, H100): the BVH's top nodes in __local memory when
# the scene block does not fit there (RTCL_X_TOP=N: the first N nodes breadth
# first, copied per work-group; N = 0 off, 63, 127, 255: 4, 8, 16 KB).
# 400, 2,000 and 20,000 random balls and the lake (Whitted), 2000x2000,
# depth 5, -w 8x8, -r 10, persistent and dynamic, three interleaved rounds,
# every image compared with N = 0's.
#   COMMIT=<commit> bash docs/results/h100-batch9/run93.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 400 2000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json > /dev/null; done
python3 tools/genbench.py lake -o $T/lake > /dev/null
declare -A S=([400]="-s $T/r400.json" [2000]="-s $T/r2000.json" [20000]="-s $T/r20000.json" [lake]="-s $(ls $T/lake/*.json)")
for round in 1 2 3; do
  for n in 400 2000 20000 lake; do
    for k in persistent dynamic; do
      for top in 0 63 127 255; do
        RTCL_X_TOP=$top $R -p $P -k $k -w 8x8 --size 2000x2000 ${S[$n]} -r 10 -q -o $T/$n-$k-$top.ppm --stats $T/s.json
        echo "round $round $n $k top $top kernel_ms $(python3 -c "
import json, re; d=json.load(open('$T/s.json')); m=re.search('RTCL_TOP_NODES=(\d+)', d['build_options'])
print(d['kernel_ms'], 'nodes', d['bvh']['nodes'], 'top', m.group(1) if m else 0, 'local', d['scene_in_local_memory'])")"
        cmp -s $T/$n-$k-0.ppm $T/$n-$k-$top.ppm || echo "  $n $k top $top: IMAGE DIFFERS"
      done
    done
  done
done
