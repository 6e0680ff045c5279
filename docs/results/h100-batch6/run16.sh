#!/bin/bash
# GPU batch 16: what the SASS suggests, through RTCL_BUILD_OPTIONS: the
# denormal fix-ups around every sqrt and reciprocal (-cl-denorms-are-zero),
# and -cl-fast-relaxed-math as an upper bound only. Persistent, default
# scene, 2,000 and 20,000 balls, -r 20, three interleaved rounds.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genscene.py --balls 2000 -o $T/r2000.json
python3 tools/genscene.py --balls 20000 -o $T/r20000.json
for round in 1 2 3; do
  for opt in none -cl-denorms-are-zero -cl-fast-relaxed-math; do
    O=""; [ $opt != none ] && O=$opt
    for sc in paper60 r2000 r20000; do
      S=""; [ $sc != paper60 ] && S="-s $T/$sc.json"
      printf "  round %s %-22s %-7s " $round $opt $sc; RTCL_BUILD_OPTIONS="$O" $R -p $P -k persistent -r 20 $S -o $T/$sc$opt.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
    done
  done
done
for sc in paper60 r2000 r20000; do
  for opt in -cl-denorms-are-zero -cl-fast-relaxed-math; do
    echo "  $sc $opt vs default: $(python3 tools/ppmdiff.py $T/${sc}none.ppm $T/$sc$opt.ppm 2>&1 | tail -1 | sed 's|.*: ||')"
  done
done
