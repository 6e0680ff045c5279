#!/bin/bash
# GPU batch 28: batch 27 found glass_mesh 2-5 % slower at $COMMIT than at
# 561d019 in two rounds (the plane grew from 48 to 64 bytes with the checker
# origin of camera-relative rendering): five interleaved rounds, -r 20, of
# dynamic and persistent on glass_mesh and paper60; and how far the new images
# are from the old (camera-relative rendering changes the last bits).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 561d019 (rtcl-561d019)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ms() { python3 -c 'import json,sys; print("%.4f" % json.load(open(sys.argv[1]))["kernel_ms"])' "$1"; }
for round in 1 2 3 4 5; do
  for s in glass_mesh paper60; do
    scene=(); [ $s != paper60 ] && scene=(-s scenes/$s.json)
    for k in dynamic persistent; do
      for b in rtcl-561d019 rtcl; do
        $G/$b -p $P -k $k -r 20 "${scene[@]}" -o $T/$b-$s-$k.ppm -q --stats $T/st.json
        printf "  round %s %-13s %-10s %-10s %s ms\n" $round $b $s $k "$(ms $T/st.json)"
      done
    done
  done
done
echo "== new against old images (dynamic, sRGB 8-bit)"
for s in glass_mesh paper60; do
  echo "  $s: $(python3 tools/imgdiff.py $T/rtcl-561d019-$s-dynamic.ppm $T/rtcl-$s-dynamic.ppm 2>&1 | tail -2 | tr '\n' ' ')"
done
