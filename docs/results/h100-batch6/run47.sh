#!/bin/bash
# GPU batch 47 (issue 27 item 6): the load-balancing study on scenes/studio.json
# (depth of field, a sphere light and a directional light with soft shadows,
# Fresnel glass and gold; 640x400, 16 samples a pixel, depth 6), --accel bvh.
# WHICH=h100 runs the full sweep on the H100 (no CPU reference: the suite
# compares it), WHICH=pocl the paper's geometries on the machine's PoCL;
# results into $OUT/$WHICH-studio (committed as docs/results/<device>-bvh-studio).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
R=$PWD/.gpu/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
if [ "$WHICH" = pocl ]; then platform=$C; extra="--no-sweep --no-serial"; else platform=$P; extra=""; fi
mkdir -p $OUT/$WHICH-studio
start=$(date +%s)
RTCL_COMMIT=$COMMIT python3 tools/experiments.py --rtcl $R -p $platform -d 0 --accel bvh \
  -s scenes/studio.json --no-reference $extra --out $OUT/$WHICH-studio 2>&1 | tail -4
echo "took $(( $(date +%s) - start )) s"
