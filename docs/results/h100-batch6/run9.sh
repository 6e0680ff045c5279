#!/bin/bash
# GPU batch 9: (A) GPU+CPU with the front-rate rule; (B) the study on the
# 2 M-triangle lake (GPU); (C) the study on PoCL (the machine's Xeon): lake,
# then the default scene with the full sweep.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
export RTCL_COMMIT=$COMMIT
echo "commit: $COMMIT"; nvidia-smi -L; lscpu | grep -E "Model name|^CPU\(s\)"
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
d() { "$@" 2>&1 | grep -E "^time|^device [0-9]|rtcl:" | sed 's/^/    /'; }
echo "== A: GPU alone, GPU in one band, GPU+CPU x3, -r 3 (dynamic spp 1024)"
d $R -p $P --spp 1024 -k dynamic -o $T/g.ppm
d $R --devices $P:0 --piece-rows 2000 --spp 1024 -k dynamic -o $T/g1.ppm
for i in 1 2 3; do d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -o $T/gc.ppm --stats $OUT/gpucpu$i.json; done
d $R --devices $P:0,$C:0 --spp 1024 -k dynamic -r 3 -o $T/gc.ppm
echo "  GPU+CPU vs GPU alone: $(python3 tools/ppmdiff.py $T/g.ppm $T/gc.ppm 2>&1 | tail -1)"
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
mkdir -p $OUT/results
echo "== B: study, lake, GPU"
python3 tools/experiments.py --rtcl $R -p $P -d 0 --accel bvh -s $T/lake/lake-10.json --size 2000x2000 --depth 5 --no-reference --no-serial --no-sweep --no-plots --out $OUT/results 2>&1 | tail -3
echo "== C: study, lake, PoCL"
python3 tools/experiments.py --rtcl $R -p $C -d 0 --accel bvh -s $T/lake/lake-10.json --size 2000x2000 --depth 5 --no-reference --no-serial --no-sweep --no-plots --out $OUT/results 2>&1 | tail -3
echo "== C: study, default scene, PoCL"
python3 tools/experiments.py --rtcl $R -p $C -d 0 --accel bvh --no-plots --out $OUT/results 2>&1 | tail -3
