#!/bin/bash
# GPU batch 18: the four-wide BVH (branch bvh4, 03dee49: 128-byte SoA nodes
# collapsed from the binary SAH tree) against the binary one (d2e1621).
# Persistent and dynamic, random balls 60 ... 20,000 and the lake; three
# interleaved rounds, -r 20 (lake -r 10); node visits; images compared.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl, binary), 03dee49 (rtcl-bvh4, four-wide)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 400 2000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json; done
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
LAKE=$T/lake/lake-10.json
for b in rtcl rtcl-bvh4; do
  for sc in paper60 r2000 r20000; do
    S=""; [ $sc != paper60 ] && S="-s $T/$sc.json"
    $G/$b -p $P -k dynamic $S -q -o $T/c.ppm --flops $T/f.npy --stats $T/c.json
    echo "  $b $sc counting: $(grep -o '"node_visits_per_ray": [0-9.]*\|"nodes": [0-9]*' $T/c.json | tr '\n' ' ')"
  done
  $G/$b -p $P --size 64x64 -v -s $LAKE -o $T/v.ppm 2>&1 | grep -E "bytes per|BVH of" | sed "s/^/  $b lake: /"
done
for round in 1 2 3; do
  for b in rtcl rtcl-bvh4; do
    for k in persistent dynamic; do
      for sc in paper60 r400 r2000 r20000; do
        S=""; [ $sc != paper60 ] && S="-s $T/$sc.json"
        printf "  round %s %-10s %-10s %-7s " $round $b $k $sc; $G/$b -p $P -k $k -r 20 $S -o $T/$b-$k-$sc.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
      done
    done
    printf "  round %s %-10s persistent lake    " $round $b; $G/$b -p $P -k persistent -r 10 -s $LAKE -o $T/$b-persistent-lake.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
  done
done
for sc in paper60 r400 r2000 r20000 lake; do echo "  $sc binary vs four-wide (persistent): $(python3 tools/ppmdiff.py $T/rtcl-persistent-$sc.ppm $T/rtcl-bvh4-persistent-$sc.ppm 2>&1 | tail -1 | sed 's|.*: ||')"; done
RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $G/rtcl-bvh4 -p $P -k persistent --size 64x64 -v -o $T/v.ppm 2>&1 | grep -iE "registers|spill" | sed 's/^/  bvh4 paper60 /'
RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $G/rtcl-bvh4 -p $P -k persistent --size 64x64 -s $T/r2000.json -v -o $T/v.ppm 2>&1 | grep -iE "registers|spill" | sed 's/^/  bvh4 r2000 /'
