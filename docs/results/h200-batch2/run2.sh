#!/bin/bash
# GPU batch 2: the BVH (spheres and triangles) against brute force, the scaling
# over random balls, a 2 M-triangle scene with mirror and glass, kernel ranking
# with --accel bvh, and the --spp probes.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
ROOT=$PWD
R=$PWD/.gpu/rtcl
T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P"
python3 tools/genbench.py random-balls --balls 60,400,2000,20000 -o $T/rb > /dev/null
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
ls $T/rb $T/lake
t() { "$@" 2>&1 | grep -E "^time:|rtcl:" | head -2 | tr '\n' ' '; echo; }
echo "== A: default scene 2000x2000, -r 20, none vs bvh"
for k in naive cyclic dynamic persistent wavefront; do
  for a in none bvh; do printf "%s %s: " $k $a; t $R -p $P -k $k --accel $a -r 20 -o $T/a.ppm; done
done
echo "== B: random balls 2000x2000, dynamic, -r 10"
for n in 60 400 2000 20000; do
  f=$(ls $T/rb/*$n*.json | head -1)
  for a in bvh none; do
    if [ $a = none ] && [ $n = 20000 ]; then continue; fi
    printf "%s balls %s: " $n $a; t $R -p $P -k dynamic --accel $a -r 10 -s $f -o $T/b.ppm
  done
done
echo "== C: lake (2,097,152 triangles, mirror lake, glass), 2000x2000 depth 5, -v load"
L=$(ls $T/lake/*.json | head -1)
/usr/bin/time -f "wall %e s" $R -p $P -s $L -v -o $T/lake.ppm 2>&1 | grep -E "rtcl:|wall|time:"
for k in naive cyclic dynamic persistent wavefront; do
  printf "lake %s bvh: " $k; t $R -p $P -k $k -s $L -r 5 -o $T/l.ppm
  $R -p $P -k $k -s $L --flops $T/lf.npy --stats $OUT/lake_$k.json -o $T/l2.ppm 2>&1 | grep -E "^(work|rays|nodes|time):"
done
echo "== D: spp probes (dynamic, 2000x2000, -r 10)"
for probe in "" "-DRTCL_PROBE_SAMPLE_WORK" "-DRTCL_PROBE_JITTER" "-DRTCL_PROBE_JITTER -DRTCL_PROBE_SHIFT"; do
  printf "spp 1 [%s]: " "$probe"; RTCL_BUILD_OPTIONS="$probe" t $R -p $P -k dynamic -r 10 --spp 1 -o $T/x.ppm
done
printf "spp 2: "; t $R -p $P -k dynamic -r 10 --spp 2 -o $T/x.ppm
printf "1000x1000 spp 1: "; t $R -p $P -k dynamic --size 1000x1000 -r 10 --spp 1 -o $T/x.ppm
printf "1000x1000 spp 4 (one pass): "; t $R -p $P -k dynamic --size 1000x1000 -r 10 --spp 4 -o $T/x.ppm
