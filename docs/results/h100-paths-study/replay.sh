#!/bin/bash
# Issue 41: the schedule replay on paths. On one GPU, the Cornell box and
# the nine-materials scene path-traced at SIZE (512x512), SPP (64) by the
# schedules whose work-items take pixels (-k naive, dynamic, persistent,
# persistent --regenerate --fetch item), each with --schedule-map (which
# work-item of which work-group started each pixel, and when); the wavefront
# forms hand out rays, not pixels, and have no map. Then, on the VM,
#   python3 tools/schedule_replay.py $OUT/SCENE-*.npy -o SCENE-replay.gif
# draws them side by side. The maps land in $OUT (12 bytes a pixel).
#   COMMIT=<commit> OUT=<folder> B=<binaries> bash docs/results/h100-paths-study/replay.sh
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b105}
SIZE=${SIZE:-512x512}; SPP=${SPP:-64}; OUT=${OUT:?OUT must name the folder for the maps}
[ -e /etc/OpenCL/vendors ] && [ -w /etc/OpenCL/vendors ] && [ -n "$(command -v nvidia-smi)" ] &&
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
P=${PLATFORM:-$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2; exit}')}
P=${P:-0}; mkdir -p $OUT; T=$(mktemp -d)
echo "commit: ${COMMIT:-unknown}; platform $P; $SIZE, $SPP spp"
for sc in cornell materials_path; do
  for k in naive dynamic persistent regenerated; do
    case $k in
      regenerated) args="-k persistent --regenerate --fetch item" ;;
      *) args="-k $k" ;;
    esac
    timeout 60 $B/rtcl -p $P -d 0 scenes/$sc.json $args --size $SIZE --spp $SPP -q \
      -o $T/$sc-$k.pfm --schedule-map $OUT/$sc-$k.npy --stats $OUT/$sc-$k.json ||
      echo "$sc $k FAILED"
    [ $k = naive ] || { cmp -s $T/$sc-$k.pfm $T/$sc-naive.pfm && echo "$sc $k: same bytes as naive" ||
      echo "$sc $k: IMAGE DIFFERS from naive"; }
  done
done
rm -rf $T
