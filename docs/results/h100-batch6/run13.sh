#!/bin/bash
# GPU batch 13: indexed triangles (16-byte triangles, shared vertices) against
# 05c7b9a's 112-byte triangles: lake (2 M triangles, mirrors, glass) and SPD
# tetra 10 (1 M), dynamic and persistent, -r 10, two rounds; bytes per
# triangle; images compared.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl) against rtcl-05c7b9a"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
python3 tools/genbench.py tetra --size 10 -o $T/tetra --image 2000x2000 > /dev/null
LAKE=$(ls $T/lake/*.json | head -1); TETRA=$(ls $T/tetra/*.json | head -1)
echo "scenes: $LAKE $TETRA"
for b in rtcl-05c7b9a rtcl; do
  for sc in $LAKE $TETRA; do
    echo "  $b $(basename $sc) -v:"; $G/$b -p $P --size 64x64 -v -s $sc -o $T/v.ppm 2>&1 | grep -E "bytes per|BVH of" | sed 's/^/    /'
  done
done
for sc in $LAKE $TETRA; do
  $R -p $P -k dynamic -s $sc -q -o $T/cnt.ppm --flops $T/f.npy --stats $T/cnt.json
  echo "  $(basename $sc) counting: $(grep -o '"rays": [0-9]*\|"node_visits_per_ray": [0-9.]*' $T/cnt.json | tr '\n' ' ')"
done
for round in 1 2; do
  for b in rtcl-05c7b9a rtcl; do
    for k in dynamic persistent; do
      for sc in $LAKE $TETRA; do
        printf "  round %s %-13s %-10s %-12s " $round $b $k $(basename $sc); $G/$b -p $P -k $k -r 10 -s $sc -o $T/$b-$k-$(basename $sc).ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
      done
    done
  done
done
for sc in $LAKE $TETRA; do
  n=$(basename $sc)
  echo "  $n old vs new (persistent): $(python3 tools/ppmdiff.py $T/rtcl-05c7b9a-persistent-$n.ppm $T/rtcl-persistent-$n.ppm 2>&1 | tail -1)"
  echo "  $n new dynamic vs persistent: $(python3 tools/ppmdiff.py $T/rtcl-dynamic-$n.ppm $T/rtcl-persistent-$n.ppm 2>&1 | tail -1)"
done
echo "  default scene, new, persistent -r 20: $($R -p $P -k persistent -r 20 -q -o $T/d.ppm --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1)"
echo "  default scene, old, persistent -r 20: $($G/rtcl-05c7b9a -p $P -k persistent -r 20 -q -o $T/d.ppm --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1)"
