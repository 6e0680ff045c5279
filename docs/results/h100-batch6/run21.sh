#!/bin/bash
# GPU batch 21: spheres in leaf order (branch leaforder, 5580e4a: a leaf of
# spheres is a range of the sphere array, no reference read) against main
# (573e566). Persistent and dynamic, default scene and random balls 400,
# 2,000, 20,000, and the lake (triangles: unchanged path, regression check);
# three interleaved rounds, -r 20 (lake -r 10); images compared; registers.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl-leaf), 573e566 (rtcl-573e566, main)"; nvidia-smi -L
P=$($G/rtcl-573e566 --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 400 2000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json; done
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
LAKE=$T/lake/lake-10.json
for b in rtcl-573e566 rtcl-leaf; do
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $G/$b -p $P -k persistent --size 64x64 -v -o $T/v.ppm 2>&1 | grep -iE "registers|spill" | head -2 | sed "s/^/  $b paper60 /"
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $G/$b -p $P -k persistent --size 64x64 -s $T/r2000.json -v -o $T/v.ppm 2>&1 | grep -iE "registers|spill" | head -2 | sed "s/^/  $b r2000 /"
done
for round in 1 2 3; do
  for b in rtcl-573e566 rtcl-leaf; do
    for k in persistent dynamic; do
      for sc in paper60 r400 r2000 r20000; do
        S=""; [ $sc != paper60 ] && S="-s $T/$sc.json"
        printf "  round %s %-13s %-10s %-7s " $round $b $k $sc; $G/$b -p $P -k $k -r 20 $S -o $T/$b-$k-$sc.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
      done
    done
    printf "  round %s %-13s persistent lake    " $round $b; $G/$b -p $P -k persistent -r 10 -s $LAKE -o $T/$b-persistent-lake.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
  done
done
for k in persistent dynamic; do for sc in paper60 r400 r2000 r20000; do echo "  $sc $k main vs leaf: $(python3 tools/ppmdiff.py $T/rtcl-573e566-$k-$sc.ppm $T/rtcl-leaf-$k-$sc.ppm 2>&1 | tail -1 | sed 's|.*: ||')"; done; done
echo "  lake main vs leaf: $(python3 tools/ppmdiff.py $T/rtcl-573e566-persistent-lake.ppm $T/rtcl-leaf-persistent-lake.ppm 2>&1 | tail -1 | sed 's|.*: ||')"
