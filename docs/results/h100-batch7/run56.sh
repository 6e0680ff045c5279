#!/bin/bash
# GPU batch 56 (issue 26): rtcl against TinyBVH on the same primary rays after
# RTCL_NO_LIGHTS (batch 55), the command of batches 45-46 and 50; into $OUT/peer.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
echo "commit: $COMMIT"; nvidia-smi -L
cd tools && RTCL_COMMIT=$COMMIT python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
  -o $OUT/peer -r 10 -k persistent,dynamic,naive --meshes tetra:8,mount:8,mount:9,lake 2>&1 | tail -8
