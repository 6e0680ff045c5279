#!/bin/bash
# GPU batch 35 (issue 25 item 5): the study again on the H100 with SIMD
# efficiency in Table 1 (measured with inline PTX in each counting run,
# modelled from the flops and the schedule map), --accel bvh on the default
# scene, into $OUT/results (committed as docs/results/nvidia-h100-80gb-hbm3-bvh-paper60).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
R=$PWD/.gpu/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
mkdir -p $OUT/results
RTCL_COMMIT=$COMMIT python3 tools/experiments.py --rtcl $R -p $P -d 0 --accel bvh --out $OUT/results 2>&1 | tail -5
