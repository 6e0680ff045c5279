#!/bin/bash
# GPU batch 10: (A) GPU+CPU with the no-small-rest and tail-margin rules;
# (B) the lake (2 M triangles) with every kernel at rtcl's default geometry
# (the study's tables ran the paper's geometries only there).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
d() { "$@" 2>&1 | grep -E "^time|^device [0-9]|rtcl:" | sed 's/^/    /'; }
echo "== A: GPU alone (x2), GPU in one band, GPU+CPU x3, -r 3 (dynamic spp 1024)"
d $R -p $P --spp 1024 -k dynamic -o $T/g.ppm
d $R -p $P --spp 1024 -k dynamic -o $T/g.ppm
d $R --devices $P:0 --piece-rows 2000 --spp 1024 -k dynamic -o $T/g1.ppm
for i in 1 2 3; do d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -o $T/gc.ppm; done
d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -r 3 -o $T/gc.ppm
echo "  GPU+CPU vs GPU alone: $(python3 tools/ppmdiff.py $T/g.ppm $T/gc.ppm 2>&1 | tail -1)"
echo "== A2: whole process wall time (bash time), GPU alone vs GPU+CPU, PNG output"
for i in 1 2; do
  TIMEFORMAT="    GPU alone wall %R s"; time $R -p $P --spp 1024 -k dynamic -q -o $T/g.png
  TIMEFORMAT="    GPU+CPU wall %R s"; time $R --devices $P:0,$C:0 --spp 1024 -k dynamic -q -o $T/gc.png
done
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
echo "== B: lake, default geometry, -r 10, then a counting run"
for k in naive cyclic dynamic persistent wavefront; do
  printf "  %-10s " $k; $R -p $P -k $k -r 10 -s $T/lake/lake-10.json -q -o $T/l.ppm --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*\|"groups": "[0-9x]*"' $T/s.json | head -2 | tr '\n' ' '
  $R -p $P -k $k -s $T/lake/lake-10.json -q -o $T/l2.ppm --flops $T/f.npy --stats $T/s2.json
  grep -o '"parallel_efficiency": [0-9.]*\|"rays": [0-9]*\|"node_visits_per_ray": [0-9.]*' $T/s2.json | tr '\n' ' '; echo
done
