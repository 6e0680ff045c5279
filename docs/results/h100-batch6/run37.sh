#!/bin/bash
# GPU batch 37 (issue 25 item 5): the study with Table 1's SIMD columns on the
# two other scenes the issue names, the lake (genbench lake, 2,097,152
# triangles, a mirror lake and glass) and glass_mesh (scenes/glass_mesh.json at
# 2000x2000: a glass icosphere and a mirror cube), --accel bvh, full sweep.
# WHICH=h100|pocl picks the device, SCENE=lake|glass_mesh the scene; results
# into $OUT/$WHICH-$SCENE (committed as docs/results/<device>-bvh-<scene>).
# The lake has no serial row (one work-item over 4 M pixels of a 2 M-triangle
# scene) and no CPU reference (it has no BVH: every ray would test 2 M
# triangles).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
R=$PWD/.gpu/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
[ "$WHICH" = pocl ] && platform=$C || platform=$P
T=$(mktemp -d)
if [ "$SCENE" = lake ]; then
  python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
  scene=(-s $T/lake/lake-10.json --no-serial --no-reference)
else
  scene=(-s scenes/glass_mesh.json --size 2000x2000)
fi
mkdir -p $OUT/$WHICH-$SCENE
start=$(date +%s)
RTCL_COMMIT=$COMMIT python3 tools/experiments.py --rtcl $R -p $platform -d 0 --accel bvh \
  "${scene[@]}" ${EXTRA:-} --out $OUT/$WHICH-$SCENE 2>&1 | tail -4
echo "took $(( $(date +%s) - start )) s"
