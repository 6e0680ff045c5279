#!/bin/bash
# GPU batch 11: GPU+CPU with the CPU waiting for the GPU's first request.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
d() { "$@" 2>&1 | grep -E "^time|^device [0-9]|rtcl:" | sed 's/^/    /'; }
echo "== GPU alone, GPU in one band, GPU+CPU x6, -r 3 (dynamic spp 1024)"
d $R -p $P --spp 1024 -k dynamic -o $T/g.ppm
d $R --devices $P:0 --piece-rows 2000 --spp 1024 -k dynamic -o $T/g1.ppm
for i in 1 2 3 4 5 6; do d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -o $T/gc.ppm; done
d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -r 3 -o $T/gc.ppm
echo "  GPU+CPU vs GPU alone: $(python3 tools/ppmdiff.py $T/g.ppm $T/gc.ppm 2>&1 | tail -1)"
echo "== whole process wall (bash time), PNG output, alternating"
for i in 1 2 3; do
  TIMEFORMAT="    GPU alone wall %R s"; time $R -p $P --spp 1024 -k dynamic -q -o $T/g.png
  TIMEFORMAT="    GPU+CPU wall %R s"; time $R --devices $P:0,$C:0 --spp 1024 -k dynamic -q -o $T/gc.png
done
