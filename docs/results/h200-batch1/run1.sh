#!/bin/bash
# H100 batch 1: antialiasing cost against N, time to image, GPU + CPU on one image.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
cd .gpu
R=$PWD/rtcl
T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L; nproc
$R --list-devices
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
echo "== A: kernel time against samples per pixel (default scene 2000x2000, -r 10, median ms)"
for k in dynamic persistent naive; do
for n in 1 2 4 8 16 32 64; do
  printf "%s spp %s: " $k $n; $R -p $P -k $k -r 10 --spp $n -o $T/a.ppm | grep -E "^time"
done; done
echo "== B: time to image, plain render, -v (PNG)"
for i in 1 2 3 4 5; do /usr/bin/time -f "wall %e s" $R -p $P -v -o $T/t.png 2>&1 | grep -E "wall|rtcl: time" | tr '\n' ';'; echo; done
echo "-- RTCL_CACHE=0"
for i in 1 2 3; do RTCL_CACHE=0 /usr/bin/time -f "wall %e s" $R -p $P -v -o $T/t.png 2>&1 | grep -E "wall|rtcl: time" | tr '\n' ';'; echo; done
echo "-- PoCL 16 cores, held-out 60 balls 1000x1000 PNG linear"
for i in 1 2 3 4 5; do /usr/bin/time -f "wall %e s" $R -p $C -s held60.json --encoding linear -v -o $T/p.png 2>&1 | grep -E "wall|rtcl: time" | tr '\n' ';'; echo; done
echo "== C: one image on the GPU, the CPU, both (default scene 2000x2000 spp 1024, dynamic)"
$R -p $C --spp 16 -o $T/c16.ppm | grep -E "^time"
for rep in 1 2; do
$R -p $P --spp 1024 -o $T/g.ppm --stats $OUT/gpu$rep.json | grep -E "^time"
$R --devices $P:0,$C:0 --spp 1024 -o $T/gc.ppm --stats $OUT/gpucpu$rep.json | grep -vE "^output"
done
$R --devices $P:0,$C:0 --split static --spp 1024 -o $T/gcs.ppm | grep -vE "^output"
$R --devices $P:0,$C:0 --piece-rows 8 --spp 1024 -o $T/gc8.ppm | grep -vE "^output"
cmp $T/g.ppm $T/gc.ppm && echo "GPU+CPU image identical to GPU" || echo "GPU+CPU image differs from GPU (expected across kinds; compare to reference tolerance)"
