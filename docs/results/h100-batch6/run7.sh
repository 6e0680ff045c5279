#!/bin/bash
# GPU batch 7: (A) what pieces cost the GPU (--devices P:0 --piece-rows N);
# (B) GPU+CPU with the GPU's smallest piece 1, 4, 8, 16 launches' worth of
# resident work-items; (C) the BVH default scene and 2,000 balls at commit
# 51970c1 (bvh merge) against now, with NVIDIA's register/spill report.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl-wN: this commit with GPU_PIECE_WAVES=N)"; nvidia-smi -L
R=$G/rtcl-w1
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
d() { "$@" 2>&1 | grep -E "^time|^device [0-9]|rtcl:" | sed 's/^/    /'; }
for k in dynamic persistent; do
  echo "== A: $k, GPU alone whole image (-p), then --devices $P:0 --piece-rows N, spp 1024"
  d $R -p $P --spp 1024 -k $k -o $T/g.ppm
  for rows in 50 100 250 500 1000 2000; do echo "  rows $rows"; d $R --devices $P:0 --piece-rows $rows --spp 1024 -k $k -o $T/g.ppm; done
done
for w in 1 4 8 16; do
  echo "== B: GPU_PIECE_WAVES=$w: GPU+CPU adaptive, dynamic spp 1024 (2 runs), then -r 3"
  d $G/rtcl-w$w --devices $P:0,$C:0 --spp 1024 -k dynamic -o $T/gc.ppm
  d $G/rtcl-w$w --devices $P:0,$C:0 --spp 1024 -k dynamic -o $T/gc.ppm
  d $G/rtcl-w$w --devices $P:0,$C:0 --spp 1024 -k dynamic -r 3 -o $T/gc.ppm
done
echo "== B: persistent, GPU_PIECE_WAVES=8"; d $G/rtcl-w8 --devices $P:0,$C:0 --spp 1024 -k persistent -o $T/gc.ppm
echo "== C: 51970c1 against now (rtcl-w1), -r 20, dynamic 8x8 and persistent"
python3 tools/genscene.py --balls 2000 -o $T/r2000.json
for b in rtcl-51970c1 rtcl-w1 rtcl-51970c1 rtcl-w1; do
  for k in dynamic persistent; do
    printf "  %-14s %-10s paper60: " $b $k; $G/$b -p $P -k $k -w 8x8 -r 20 -o $T/c.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
    printf "  %-14s %-10s r2000:   " $b $k; $G/$b -p $P -k $k -w 8x8 -r 20 -s $T/r2000.json -o $T/c.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
  done
done
for b in rtcl-51970c1 rtcl-w1; do
  echo "  $b build report (-cl-nv-verbose), dynamic bvh paper60:"
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $G/$b -p $P -k dynamic --size 64x64 -v -o $T/v.ppm 2>&1 | grep -iE "registers|spill|stack|options" | sed 's/^/    /'
done
