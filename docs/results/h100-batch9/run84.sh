#!/bin/bash
# GPU batch 84 (issue 26, H100): where rtcl stands at HEAD. (1) The sphere
# targets: the default scene (60 balls), 2,000 and 20,000 random balls
# (genscene, seed 2009), 2000x2000, depth 5, -w 8x8, -r 10, persistent and
# dynamic, three interleaved rounds. (2) rtcl against TinyBVH on the same
# primary rays, run68.sh's comparison (programs built from source, one mesh
# at a time). Needs .gpu/peer and the binaries in .gpu/.
#   COMMIT=<commit> bash docs/results/h100-batch9/run84.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 2000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json; done
declare -A S=([60]="" [2000]="-s $T/r2000.json" [20000]="-s $T/r20000.json")
for n in 60 2000 20000; do for k in persistent dynamic; do
  $R -p $P -k $k -w 8x8 --size 2000x2000 ${S[$n]} --size 64x64 -q -o $T/prime.ppm; done; done
for round in 1 2 3; do
  for n in 60 2000 20000; do
    for k in persistent dynamic; do
      $R -p $P -k $k -w 8x8 --size 2000x2000 ${S[$n]} -r 10 -q -o $T/$n-$k.ppm --stats $T/s.json
      echo "round $round balls $n $k kernel_ms $(python3 -c "import json; d=json.load(open('$T/s.json')); print(d['kernel_ms'], d['build_options'] if '$round' == '1' else '')")"
    done
    cmp -s $T/$n-persistent.ppm $T/$n-dynamic.ppm && echo "  balls $n: images identical" || echo "  balls $n: IMAGES DIFFER"
  done
done
cd tools
for mesh in tetra:8 mount:8 mount:9 lake; do
  RTCL_CACHE=0 RTCL_COMMIT=$COMMIT timeout 300 python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
    -o $T/peer-${mesh/:/-} -r 10 -k persistent,dynamic,naive --meshes $mesh 2>&1 | tail -6
  (cd $T && tar czf $OUT/batch84.tgz --exclude='*.ppm' --exclude='*.bin' --exclude='*.ply' --exclude='*.obj' peer-*)
done
