#!/bin/bash
# GPU batch 19: two H200s on one image (issue 13's two-GPU case, never lent
# before): one GPU against both, default scene 2000x2000, spp 1024, dynamic.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
$R --list-devices
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
d() { "$@" 2>&1 | grep -E "^time|^device [0-9]|rtcl:" | sed 's/^/    /'; }
for i in 1 2; do
  echo "  one GPU:"; d $R -p $P -d 0 --spp 1024 -k dynamic -o $T/g.ppm
  echo "  two GPUs:"; d $R --devices $P:0,$P:1 --spp 1024 -k dynamic -o $T/gg.ppm
done
echo "  images: $(python3 tools/ppmdiff.py $T/g.ppm $T/gg.ppm 2>&1 | tail -1 | sed 's|.*: ||')"
for i in 1 2; do
  TIMEFORMAT="    one GPU wall %R s"; time $R -p $P -d 0 --spp 1024 -k dynamic -q -o $T/g.png
  TIMEFORMAT="    two GPUs wall %R s"; time $R --devices $P:0,$P:1 --spp 1024 -k dynamic -q -o $T/gg.png
done
