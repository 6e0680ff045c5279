#!/bin/bash
# GPU batch 22: the scaling curve over random balls (60 ... 20,000, seed 2009)
# with the spheres in leaf order (rtcl, $COMMIT) against main before them
# (rtcl-573e566); persistent and dynamic, three interleaved rounds, -r 20.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 573e566 (rtcl-573e566)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
for n in 60 200 400 1000 2000 5000 20000; do python3 tools/genscene.py --balls $n -o $T/r$n.json; done
for round in 1 2 3; do
  for b in rtcl-573e566 rtcl; do
    for k in persistent dynamic; do
      for n in 60 200 400 1000 2000 5000 20000; do
        printf "  round %s %-13s %-10s %6s " $round $b $k $n; $G/$b -p $P -k $k -r 20 -s $T/r$n.json -o $T/$b-$k-$n.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
      done
    done
  done
done
for n in 60 20000; do echo "  r$n persistent old vs new: $(python3 tools/ppmdiff.py $T/rtcl-573e566-persistent-$n.ppm $T/rtcl-persistent-$n.ppm 2>&1 | tail -1 | sed 's|.*: ||')"; done
