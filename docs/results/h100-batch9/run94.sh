#!/bin/bash
# GPU batch 94 (issue 26, H100): the SAH's node cost and leaf size for
# spheres, re-measured now that a leaf's spheres are read in order (batch 21)
# and cheaper to test. Host builds of the same commit with -DBVH_NODE_COST=C
# -DBVH_TRIANGLE_COST=C -DBVH_MAX_LEAF=L (the triangle cost kept equal to the
# node cost, as main's 3 and 3, so that mesh trees keep their balance):
# A main (3, 8), B (6, 8), C (6, 16), D (4.5, 12). The default scene, 400,
# 2,000 and 20,000 balls, 2000x2000, depth 5, -w 8x8, -r 10, persistent,
# three interleaved rounds; the lake's Whitted rays once each.
#   COMMIT=<commit> bash docs/results/h100-batch9/run94.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; T=$(mktemp -d)
declare -A B=([A]=$G/rtcl [B]=$G/rtcl-B [C]=$G/rtcl-C [D]=$G/rtcl-D)
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 400 2000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json > /dev/null; done
python3 tools/genbench.py lake -o $T/lake > /dev/null
declare -A S=([60]="" [400]="-s $T/r400.json" [2000]="-s $T/r2000.json" [20000]="-s $T/r20000.json" [lake]="-s $(ls $T/lake/*.json)")
for round in 1 2 3; do
  for n in 60 400 2000 20000; do
    for v in A B C D; do
      ${B[$v]} -p $P -k persistent -w 8x8 --size 2000x2000 ${S[$n]} -r 10 -q -o $T/$n-$v.ppm --stats $T/s.json
      echo "round $round $n $v kernel_ms $(python3 -c "import json; d=json.load(open('$T/s.json')); b=d['bvh']; print(d['kernel_ms'], 'nodes', b['nodes'], 'depth', b['depth'])")"
      cmp -s $T/$n-A.ppm $T/$n-$v.ppm || echo "  $n $v: IMAGE DIFFERS"
    done
  done
done
for v in A B C D; do
  ${B[$v]} -p $P -k persistent -w 8x8 --size 2000x2000 ${S[lake]} -r 10 -q -o $T/lake-$v.ppm --stats $T/s.json
  echo "lake $v kernel_ms $(python3 -c "import json; d=json.load(open('$T/s.json')); b=d['bvh']; print(d['kernel_ms'], 'nodes', b['nodes'], 'build_ms', b['build_ms'])")"
  cmp -s $T/lake-A.ppm $T/lake-$v.ppm || echo "  lake $v: IMAGE DIFFERS"
done
