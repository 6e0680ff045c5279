#!/bin/bash
# GPU batch 89 (issue 26, H100): Whitted rays (depth 5, the scenes' lights,
# shadows, reflections) on every scene of the set of a million triangles or
# more: genbench tetra 10, mount 10 and the lake, 2000x2000.
# The rays of every kind from a counting run (-k dynamic --flops), then the
# median kernel time of -r 10, persistent and naive, two interleaved rounds.
#   COMMIT=<commit> bash docs/results/h100-batch9/run89.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py tetra --size 10 -o $T/tetra > /dev/null
python3 tools/genbench.py mount --size 10 -o $T/mount > /dev/null
python3 tools/genbench.py lake -o $T/lake > /dev/null
declare -A S
for m in tetra mount lake; do S[$m]=$(ls $T/$m/*.json); done
for m in tetra mount lake; do
  $R -p $P -k dynamic -s ${S[$m]} --size 2000x2000 -q -o $T/c.ppm --flops $T/f.npy --stats $T/c-$m.json
  python3 -c "import json; d=json.load(open('$T/c-$m.json')); print('$m: depth', d['max_depth'], 'rays', d['rays'], 'node visits per ray %.2f' % d['node_visits_per_ray'])"
done
for round in 1 2; do
  for m in tetra mount lake; do
    for k in persistent naive; do
      $R -p $P -k $k -s ${S[$m]} --size 2000x2000 -r 10 -q -o $T/x.ppm --stats $T/s.json
      python3 -c "
import json; d=json.load(open('$T/s.json')); c=json.load(open('$T/c-$m.json'))
print('round $round $m $k: %.3f ms, %.2f G rays/s' % (d['kernel_ms'], c['rays'] / d['kernel_ms'] / 1e6))"
    done
  done
done
