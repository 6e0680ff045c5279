#!/bin/bash
# GPU batch 8: (A) the BVH scenes at 51970c1 (bvh merge), a9fa9f1 (before
# -DRTCL_NO_TRIANGLES) and now, register caps; (B) GPU+CPU with 16-launch GPU
# pieces; (C) the study (experiments.py --accel bvh) on the default scene.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl-w1 = a9fa9f1)"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
d() { "$@" 2>&1 | grep -E "^time|^device [0-9]|rtcl:" | sed 's/^/    /'; }
python3 tools/genscene.py --balls 2000 -o $T/r2000.json
echo "== A: -r 20, -w 8x8, kernel_ms median"
for round in 1 2; do
  for b in rtcl-51970c1 rtcl-w1 rtcl; do
    for k in dynamic persistent; do
      printf "  %-14s %-10s paper60: " $b $k; $G/$b -p $P -k $k -w 8x8 -r 20 -o $T/c.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
      printf "  %-14s %-10s r2000:   " $b $k; $G/$b -p $P -k $k -w 8x8 -r 20 -s $T/r2000.json -o $T/c.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
    done
  done
done
for cap in 64 96 128; do
  for k in dynamic persistent; do
    printf "  rtcl maxrregcount=%s %-10s paper60: " $cap $k; RTCL_BUILD_OPTIONS=-cl-nv-maxrregcount=$cap $R -p $P -k $k -w 8x8 -r 20 -o $T/c.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
    printf "  rtcl maxrregcount=%s %-10s r2000:   " $cap $k; RTCL_BUILD_OPTIONS=-cl-nv-maxrregcount=$cap $R -p $P -k $k -w 8x8 -r 20 -s $T/r2000.json -o $T/c.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
  done
done
for extra in "" "-cl-nv-maxrregcount=96" "-cl-nv-maxrregcount=128"; do
  echo "  rtcl build report $extra (dynamic bvh paper60):"
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS="-cl-nv-verbose $extra" $R -p $P -k dynamic --size 64x64 -v -o $T/v.ppm 2>&1 | grep -iE "registers|spill" | sed 's/^/    /'
done
echo "== B: GPU+CPU, dynamic spp 1024, 16-launch GPU pieces"
d $R -p $P --spp 1024 -k dynamic -o $T/g.ppm
d $R --devices $P:0 --piece-rows 2000 --spp 1024 -k dynamic -o $T/g1.ppm
for i in 1 2 3; do d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -o $T/gc.ppm; done
d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -r 3 -o $T/gc.ppm
cmp $T/g.ppm $T/g1.ppm && echo "  GPU whole image and GPU in one band: identical"
echo "== C: study, default scene, --accel bvh"
mkdir -p $OUT/results
python3 tools/experiments.py --rtcl $R -p $P -d 0 --accel bvh --out $OUT/results 2>&1 | tail -5
