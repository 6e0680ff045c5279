#!/bin/bash
# GPU batch 29: where batch 28's 4-8 % on glass_mesh comes from. At $COMMIT
# (new), new with cl/shade.cl's checker-origin add taken out (RTCL_CL_DIR
# .gpu/cl-noorigin: the image's checker is wrong, the time tells), and
# 561d019 (old): dynamic and persistent on glass_mesh, five interleaved
# rounds, -r 20; then the registers and spills of each (-cl-nv-verbose).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 561d019 (rtcl-561d019)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ms() { python3 -c 'import json,sys; print("%.4f" % json.load(open(sys.argv[1]))["kernel_ms"])' "$1"; }
run() { # variant, rtcl arguments...
  local v=$1; shift
  case $v in
    old) $G/rtcl-561d019 "$@" ;;
    new) $G/rtcl "$@" ;;
    noorigin) RTCL_CL_DIR=$G/cl-noorigin $G/rtcl "$@" ;;
  esac
}
for round in 1 2 3 4 5; do
  for k in dynamic persistent; do
    for v in old new noorigin; do
      run $v -p $P -k $k -r 20 -s scenes/glass_mesh.json -o $T/$v-$k.ppm -q --stats $T/st.json
      printf "  round %s %-9s %-10s %s ms\n" $round $v $k "$(ms $T/st.json)"
    done
  done
done
for v in old new noorigin; do
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose run $v -p $P -k dynamic -s scenes/glass_mesh.json --size 64x64 -v -o $T/a.ppm 2>&1 | grep -iE "registers|spill" | sed "s/^/  $v /" | head -4
done
