#!/bin/bash
# GPU batch 30: batch 29 ruled out the checker-origin add. Here glass_mesh
# moved so that its eye is the origin (.gpu/gm_eye0.json: every position minus
# the eye; then the device's coordinates are the world's in both binaries) and
# glass_mesh without its plane (.gpu/gm_noplane.json), old (561d019) against
# new ($COMMIT), dynamic, four interleaved rounds, -r 20.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 561d019 (rtcl-561d019)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ms() { python3 -c 'import json,sys; print("%.4f" % json.load(open(sys.argv[1]))["kernel_ms"])' "$1"; }
for round in 1 2 3 4; do
  for s in scenes/glass_mesh.json .gpu/gm_eye0.json .gpu/gm_noplane.json; do
    for b in rtcl-561d019 rtcl; do
      $G/$b -p $P -k dynamic -r 20 -s $s -o $T/x.ppm -q --stats $T/st.json
      printf "  round %s %-13s %-22s %s ms\n" $round $b $s "$(ms $T/st.json)"
    done
  done
done
