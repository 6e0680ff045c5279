#!/bin/bash
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
T=$(mktemp -d); R=$PWD/.gpu/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
for k in dynamic persistent naive; do
  printf "%s GPU alone: " $k; $R -p $P --spp 1024 -k $k -o $T/g.ppm | grep -E "^time"
  printf "%s --devices GPU only: " $k; $R --devices $P:0 --spp 1024 -k $k -o $T/g1.ppm | grep -E "^time|^device 0" | tr '\n' ' '; echo
  echo "$k GPU+CPU:"; $R --devices $P:0,$C:0 --spp 1024 -k $k -o $T/gc.ppm | grep -E "^time|^device [01]"
done
printf "dynamic GPU+CPU --piece-rows 1000 (2 bands of 1000 rows): "; $R --devices $P:0,$C:0 --spp 64 -k dynamic --piece-rows 1000 -o $T/x.ppm | grep -E "^time|^device" | tr '\n' ' '; echo
printf "dynamic GPU alone spp 64: "; $R -p $P --spp 64 -k dynamic -o $T/x.ppm | grep -E "^time"
