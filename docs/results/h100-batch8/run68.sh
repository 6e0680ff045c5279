#!/bin/bash
# GPU batch 68 (issue 26): rtcl against TinyBVH on the same primary rays
# with the program cache fixed (f3ae66c; batch 60 found cached and fresh
# programs equally fast since): run61's comparison, programs built from
# source (RTCL_CACHE=0), one mesh at a time, each mesh's results tarred as
# soon as they exist (a time-out keeps what was done). Needs .gpu/peer (the
# peer's folder) and the binaries in .gpu/.
#   COMMIT=<commit> bash docs/results/h100-batch8/run68.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
T=$(mktemp -d)
cd tools
for mesh in tetra:8 mount:8 mount:9 lake; do
  RTCL_CACHE=0 RTCL_COMMIT=$COMMIT timeout 300 python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
    -o $T/peer-${mesh/:/-} -r 10 -k persistent,dynamic,naive --meshes $mesh 2>&1 | tail -6
  tar czf $OUT/batch68.tgz -C $T .
done
