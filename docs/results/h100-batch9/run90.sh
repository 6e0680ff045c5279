#!/bin/bash
# GPU batch 90 (issue 26, H100): the compressed eight-wide tree (bvh_compress,
# RTCL_TEST_BVH8=1) against the binary tree, same binary, same rays.
# (1) Spheres: the default scene (60 balls), 400, 2,000 and 20,000 random
# balls (genscene, seed 2009), 2000x2000, depth 5, -w 8x8, -r 10, persistent
# and dynamic, three interleaved rounds, the two trees' images compared.
# (2) Primary rays through meshes, the TinyBVH comparison (peer_compare.py)
# with each tree: tetra 8 and the lake. (3) The lake's Whitted rays.
# (4) NVIDIA's register and spill report for both programs.
#   COMMIT=<commit> bash docs/results/h100-batch9/run90.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 400 2000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json > /dev/null; done
declare -A S=([60]="" [400]="-s $T/r400.json" [2000]="-s $T/r2000.json" [20000]="-s $T/r20000.json")
for n in 60 2000; do for w in 2 8; do
  RTCL_TEST_BVH8=$([ $w = 8 ] && echo 1 || echo 0) RTCL_BUILD_OPTIONS=-cl-nv-verbose \
    $R -p $P -k persistent -w 8x8 --size 64x64 ${S[$n]} -v -q -o $T/prime.ppm 2>&1 |
    grep -iE "registers|spill|stack frame" | head -4 | sed "s/^/  balls $n tree $w: /"
done; done
for round in 1 2 3; do
  for n in 60 400 2000 20000; do
    for k in persistent dynamic; do
      for w in 2 8; do
        RTCL_TEST_BVH8=$([ $w = 8 ] && echo 1 || echo 0) \
          $R -p $P -k $k -w 8x8 --size 2000x2000 ${S[$n]} -r 10 -q -o $T/$n-$k-$w.ppm --stats $T/s.json
        echo "round $round balls $n $k tree $w kernel_ms $(python3 -c "import json; d=json.load(open('$T/s.json')); print(d['kernel_ms'], d['bvh']['device_nodes'], d['bvh']['bytes'])")"
      done
      cmp -s $T/$n-$k-2.ppm $T/$n-$k-8.ppm && echo "  balls $n $k: the trees' images identical" || echo "  balls $n $k: IMAGES DIFFER"
    done
  done
done
python3 tools/genbench.py lake -o $T/lake > /dev/null
L=$(ls $T/lake/*.json)
for round in 1 2; do for w in 2 8; do
  RTCL_TEST_BVH8=$([ $w = 8 ] && echo 1 || echo 0) \
    $R -p $P -k persistent -s $L --size 2000x2000 -r 10 -q -o $T/lake-$w.ppm --stats $T/s.json
  echo "round $round lake whitted tree $w kernel_ms $(python3 -c "import json; d=json.load(open('$T/s.json')); print(d['kernel_ms'], d['bvh']['device_nodes'], d['bvh']['bytes'])")"
done; cmp -s $T/lake-2.ppm $T/lake-8.ppm && echo "  lake: identical" || echo "  lake: IMAGES DIFFER"; done
cd tools
for mesh in tetra:8 lake; do for w in 2 8; do
  echo "== $mesh tree $w"
  RTCL_TEST_BVH8=$([ $w = 8 ] && echo 1 || echo 0) RTCL_CACHE=0 RTCL_COMMIT=$COMMIT timeout 300 \
    python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
    -o $T/peer-${mesh/:/-}-$w -r 10 -k persistent,naive --meshes $mesh 2>&1 | tail -5
done; done
(cd $T && tar czf $OUT/batch90.tgz --exclude='*.ppm' --exclude='*.bin' --exclude='*.ply' --exclude='*.obj' peer-*)
