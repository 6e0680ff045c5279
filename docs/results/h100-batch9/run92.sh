#!/bin/bash
# GPU batch 92 (issue 26, H100): leaves postponed until the warp holds one
# each (Aila and Laine 2009's speculative while-while) in the binary tree,
# with NVIDIA's warp vote through inline PTX (RTCL_SPECULATIVE RTCL_NV_PTX;
# inline PTX builds in NVIDIA's OpenCL, probe: vote.sync.ballot gave the
# expected mask); without the vote (RTCL_SPECULATIVE alone: each work-item
# tests its leaf at once, a while-while loop) as a control. Spheres (the
# default scene, 2,000 and 20,000 balls) and the lake, 2000x2000, depth 5,
# -w 8x8, -r 10, persistent and dynamic, three interleaved rounds; then the
# TinyBVH comparison's primary rays (tetra 8, the lake) with each.
#   COMMIT=<commit> bash docs/results/h100-batch9/run92.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 2000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json > /dev/null; done
python3 tools/genbench.py lake -o $T/lake > /dev/null
declare -A S=([60]="" [2000]="-s $T/r2000.json" [20000]="-s $T/r20000.json" [lake]="-s $(ls $T/lake/*.json)")
declare -A V=([plain]="" [spec]="-DRTCL_SPECULATIVE -DRTCL_NV_PTX" [while]="-DRTCL_SPECULATIVE")
for v in plain spec; do
  RTCL_BUILD_OPTIONS="-cl-nv-verbose ${V[$v]}" $R -p $P -k persistent -w 8x8 --size 64x64 -v -o $T/prime.ppm 2>&1 |
    grep -iE "registers|spill" | head -2 | sed "s/^/  $v: /"
done
for round in 1 2 3; do
  for n in 60 2000 20000 lake; do
    for k in persistent dynamic; do
      for v in plain spec while; do
        RTCL_BUILD_OPTIONS="${V[$v]}" \
          $R -p $P -k $k -w 8x8 --size 2000x2000 ${S[$n]} -r 10 -q -o $T/$n-$k-$v.ppm --stats $T/s.json
        echo "round $round $n $k $v kernel_ms $(python3 -c "import json; d=json.load(open('$T/s.json')); print(d['kernel_ms'])")"
        cmp -s $T/$n-$k-plain.ppm $T/$n-$k-$v.ppm || echo "  $n $k $v: IMAGE DIFFERS"
      done
    done
  done
done
cd tools
for mesh in tetra:8 lake; do for v in plain spec; do
  echo "== $mesh $v"
  RTCL_BUILD_OPTIONS="${V[$v]}" RTCL_CACHE=0 RTCL_COMMIT=$COMMIT timeout 300 \
    python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
    -o $T/peer-${mesh/:/-}-$v -r 10 -k persistent,naive --meshes $mesh 2>&1 | tail -3
done; done
(cd $T && tar czf $OUT/batch92.tgz --exclude='*.ppm' --exclude='*.bin' --exclude='*.ply' --exclude='*.obj' --exclude=peer --exclude=meshes peer-*)
