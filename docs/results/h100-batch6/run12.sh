#!/bin/bash
# GPU batch 12: -DRTCL_ONE_SAMPLE against the BVH merge (51970c1), default
# scene and 2,000 balls, dynamic and persistent, -r 20, three rounds; spills.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genscene.py --balls 2000 -o $T/r2000.json
python3 tools/genscene.py --balls 20000 -o $T/r20000.json
for round in 1 2 3; do
  for b in rtcl-51970c1 rtcl; do
    for k in dynamic persistent; do
      for sc in paper60 r2000 r20000; do
        S=""; [ $sc != paper60 ] && S="-s $T/$sc.json"
        printf "  round %s %-13s %-10s %-8s " $round $b $k $sc; $G/$b -p $P -k $k -w 8x8 -r 20 $S -o $T/c.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
      done
    done
  done
done
for b in rtcl-51970c1 rtcl; do
  echo "  $b build report (dynamic bvh paper60):"
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $G/$b -p $P -k dynamic --size 64x64 -v -o $T/v.ppm 2>&1 | grep -iE "registers|spill|options" | sed 's/^/    /'
done
