#!/bin/bash
# GPU batch 6: why GPU+CPU in one process is slower than the GPU alone
# (kernel time vs busy time per device, piece-size curve, CPU load probes),
# and the random-ball scaling curve on the H200.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
R=$PWD/.gpu/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
S="--spp 1024 -k dynamic"
d() { "$@" 2>&1 | grep -E "^time|^device [0-9]|rtcl:" | sed 's/^/    /'; }
mon() { nvidia-smi --query-gpu=utilization.gpu,clocks.sm,power.draw --format=csv,noheader -lms 100 > $T/mon.txt & MP=$!; }
endmon() { kill $MP; wait $MP 2>/dev/null; awk -F', ' '{u+=$1; c+=$2; n++} END {printf "    nvidia-smi: mean utilization %.0f %%, mean SM clock %.0f MHz over %d samples\n", u/n, c/n, n}' $T/mon.txt; }
echo "== A1: GPU alone, plain path"; mon; d $R -p $P $S -o $T/g.ppm; endmon
echo "== A2: GPU alone, --devices (adaptive pieces)"; mon; d $R --devices $P:0 $S -o $T/g1.ppm; endmon
for rows in 100 250 500 1000; do
  echo "== A3: GPU alone, --piece-rows $rows"; d $R --devices $P:0 $S --piece-rows $rows -o $T/g2.ppm
done
echo "== B1: GPU+CPU adaptive (x2)"; mon; d $R --devices $P:0,$C:0 $S -o $T/gc.ppm; endmon
d $R --devices $P:0,$C:0 $S -o $T/gc.ppm
echo "== B2: GPU+CPU, POCL_MAX_PTHREAD_COUNT=4"; POCL_MAX_PTHREAD_COUNT=4 d $R --devices $P:0,$C:0 $S -o $T/gc.ppm
echo "== B3: GPU+CPU, CPU idles 9x its piece time after each piece (RTCL_TEST_SLOW_DEVICE=1:x10)"
RTCL_TEST_SLOW_DEVICE=1:x10 d $R --devices $P:0,$C:0 $S -o $T/gc.ppm
echo "== B4: GPU+CPU persistent"; d $R --devices $P:0,$C:0 --spp 1024 -k persistent -o $T/gc.ppm
echo "== B5: GPU alone persistent --devices"; d $R --devices $P:0 --spp 1024 -k persistent -o $T/gc.ppm
echo "== C: random balls (genscene, seed 2009), 2000x2000, depth 5, -r 10, bvh"
for n in 60 200 400 1000 2000 5000 20000; do
  python3 tools/genscene.py --balls $n -o $T/r$n.json
  for k in dynamic persistent; do
    printf "  %5d balls %-10s " $n $k
    $R -p $P -k $k -r 10 -s $T/r$n.json -o $T/r.ppm -q --stats $T/st.json 2>&1 | grep -E "^time" | tr '\n' ' '
    grep -o '"kernel_ms": [0-9.]*' $T/st.json | head -1
  done
  $R -p $P -k dynamic -s $T/r$n.json -o $T/r.ppm -q --flops $T/f.npy --stats $T/st2.json >/dev/null 2>&1
  echo "        $(grep -o '"node_visits_per_ray": [0-9.]*' $T/st2.json) $(grep -o '"nodes": [0-9]*' $T/st2.json) $(grep -o '"scene_in_local_memory": [a-z]*' $T/st2.json)"
done
