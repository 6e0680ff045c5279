#!/bin/bash
# GPU batch 91 (issue 26, H100): why batch 90's eight-wide tree is slower.
# NVIDIA's register and spill report for both trees, then variants of the
# eight-wide visit (build options of the experiment): the byte to float by
# I2F (RTCL_BVH8_I2F) instead of 2^23 + q - 2^23, and empty slots skipped
# (RTCL_BVH8_SKIP_EMPTY); 60 and 20,000 balls, 2000x2000, persistent, -r 10,
# three interleaved rounds.
#   COMMIT=<commit> bash docs/results/h100-batch9/run91.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genscene.py --balls 20000 -o $T/r20000.json > /dev/null
declare -A S=([60]="" [20000]="-s $T/r20000.json")
declare -A V=([2]="0|" [8]="1|" [8i]="1|-DRTCL_BVH8_I2F" [8s]="1|-DRTCL_BVH8_SKIP_EMPTY" [8is]="1|-DRTCL_BVH8_I2F -DRTCL_BVH8_SKIP_EMPTY")
for v in 2 8 8i 8s 8is; do
  RTCL_TEST_BVH8=${V[$v]%%|*} RTCL_BUILD_OPTIONS="-cl-nv-verbose ${V[$v]#*|}" \
    $R -p $P -k persistent -w 8x8 --size 64x64 -v -o $T/prime.ppm 2>&1 |
    grep -iE "registers|spill|stack frame" | head -3 | sed "s/^/  variant $v: /"
done
for round in 1 2 3; do
  for n in 60 20000; do
    for v in 2 8 8i 8s 8is; do
      RTCL_TEST_BVH8=${V[$v]%%|*} RTCL_BUILD_OPTIONS="${V[$v]#*|}" \
        $R -p $P -k persistent -w 8x8 --size 2000x2000 ${S[$n]} -r 10 -q -o $T/$n-$v.ppm --stats $T/s.json
      echo "round $round balls $n variant $v kernel_ms $(python3 -c "import json; d=json.load(open('$T/s.json')); print(d['kernel_ms'])")"
      cmp -s $T/$n-2.ppm $T/$n-$v.ppm || echo "  balls $n variant $v: IMAGE DIFFERS"
    done
  done
done
