#!/bin/bash
# Experiment (not committed code): do per-pass host waits slow the GPU beside PoCL?
# rtcl = the commit; rtcl-bigpass = the same with RENDER_PASS_PIXEL_SAMPLES 2^26 (16x fewer launches).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
for b in rtcl rtcl-bigpass; do
  R=$PWD/.gpu/$b
  P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
  C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
  for rep in 1 2; do
    printf "%s GPU alone: " $b; $R -p $P --spp 1024 -k dynamic -o $T/g.ppm | grep -E "^time"
    echo "$b GPU+CPU:"; $R --devices $P:0,$C:0 --spp 1024 -k dynamic -o $T/gc.ppm | grep -E "^time|^device [01]"
  done
  echo "$b GPU alone while PoCL renders another image:"
  $R -p $C --spp 64 -k dynamic -o $T/bg.ppm > /dev/null 2>&1 & BG=$!; sleep 2
  $R -p $P --spp 1024 -k dynamic -o $T/g2.ppm | grep -E "^time"; kill $BG; wait
done
