#!/bin/bash
# GPU batch 88 (issue 26, H100): rtcl against TinyBVH on the same primary
# rays at f58afbc on the rest of the 0.1-3 M-triangle set (tetra 9 and 10,
# mount 10), run68.sh's
# comparison: programs built from source, one mesh at a time.
#   COMMIT=<commit> bash docs/results/h100-batch9/run88.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
T=$(mktemp -d)
cd tools
for mesh in tetra:9 tetra:10 mount:10; do
  RTCL_CACHE=0 RTCL_COMMIT=$COMMIT timeout 300 python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
    -o $T/peer-${mesh/:/-} -r 10 -k persistent,dynamic,naive --meshes $mesh 2>&1 | tail -6
  (cd $T && tar czf $OUT/batch88.tgz --exclude='*.ppm' --exclude='*.bin' --exclude='*.ply' --exclude='*.obj' peer-*)
done
