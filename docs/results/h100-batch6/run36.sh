#!/bin/bash
# GPU batch 36 (issue 25 item 5): the study on the H100 machine's PoCL (its
# 16-core Xeon) and again on the H100, --accel bvh on the default scene, with
# Table 1's SIMD columns (measured: not measurable on PoCL; modelled
# everywhere) and the work-items that traced pixels, into
# $OUT/pocl and $OUT/h100 (committed as docs/results/pocl-intel-r-xeon-r-processor-bvh-paper60
# and nvidia-h100-80gb-hbm3-bvh-paper60). WHICH=pocl|h100 runs one of them.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
R=$PWD/.gpu/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
[ "$WHICH" = pocl ] && platform=$C || platform=$P
mkdir -p $OUT/$WHICH
RTCL_COMMIT=$COMMIT python3 tools/experiments.py --rtcl $R -p $platform -d 0 --accel bvh --out $OUT/$WHICH 2>&1 | tail -4
