#!/bin/bash
# Issue 41: path regeneration's three counter schemes side by side on one
# GPU (batch 99 measured item and subgroup): -k persistent --regenerate
# --fetch item (a global atomic per work-item), group (a wait-free block per
# work-group in __local memory) and subgroup (one atomic a warp), with -k
# dynamic as the reference image, on scenes/cornell.json,
# scenes/studio_path.json and scenes/materials_path.json at SIZE 1024x1024,
# SPP 64, -r 5 (median kernel time of 5 after a warm-up), two interleaved
# rounds; every image compared with dynamic's by cmp. About 60-90 s.
#   COMMIT=<commit> OUT=<folder> B=<binaries> bash docs/results/h100-paths-study/run-fetch.sh
# On PoCL (a check of the script): PLATFORM=0 SIZE=32x32 SPP=2 ... run-fetch.sh
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b105}
SIZE=${SIZE:-1024x1024}; SPP=${SPP:-64}; OUT=${OUT:?OUT must name the folder for the results}
[ -e /etc/OpenCL/vendors ] && [ -w /etc/OpenCL/vendors ] && [ -n "$(command -v nvidia-smi)" ] &&
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
[ -x $B/rtcl-meshread ] && export RTCL_MESHREAD=$B/rtcl-meshread
P=${PLATFORM:-$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2; exit}')}
P=${P:-0}; mkdir -p $OUT; T=$(mktemp -d)
exec > >(tee $OUT/fetch.txt) 2>&1
echo "commit: ${COMMIT:-unknown}; platform $P; $SIZE, $SPP spp"; nvidia-smi -L 2> /dev/null
for round in 1 2; do
  for sc in cornell studio_path materials_path; do
    for k in dynamic item group subgroup; do
      case $k in
        dynamic) args="-k dynamic" ;;
        *) args="-k persistent --regenerate --fetch $k" ;;
      esac
      st=$OUT/$sc-$k-$round.json
      timeout 90 $B/rtcl -p $P -d 0 scenes/$sc.json $args --size $SIZE --spp $SPP -r 5 -q \
        -o $T/$sc-$k.pfm --stats $st > $T/log 2>&1 || { echo "$sc $k FAILED"; cat $T/log; continue; }
      echo "$sc $k round $round: $(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print('%.2f ms (rounds %.2f-%.2f)' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max']))" $st)"
      [ $k = dynamic ] || { cmp -s $T/$sc-$k.pfm $T/$sc-dynamic.pfm && echo "  same bytes as dynamic" ||
        echo "  IMAGE DIFFERS from dynamic"; }
    done
  done
done
rm -rf $T
