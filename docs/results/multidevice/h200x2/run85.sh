#!/bin/bash
# Issue 28, batch 85 (two H200s): 7bc52c9 (buffers placed on the device in
# the set-up; under --mpi each rank's devices opened before the clock)
# against 35caf1c (.gpu/rtcl-35c, .gpu/rtcl-mpi-35c). MPI one rank against
# two, unbound, on the default scene (2048 spp, three rounds) and the lake
# (256 spp, two rounds); a single render (no -r) of the lake on one GPU in one
# process; the default scene on one GPU and two at -r 3 as a check.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run85.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d); O=$T/json85; mkdir -p $O
echo "commit: $COMMIT (old: 35caf1c)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
D="-k dynamic --size 2000x2000 --spp 2048"
python3 tools/genbench.py lake -o $T/lake > /dev/null
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
$G/rtcl -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm; $G/rtcl-35c -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm
$G/rtcl -p $P -d 0 $D -q -o $T/D.ppm
$G/rtcl -p $P -d 0 $L -q -o $T/L.ppm
. $G/ompi/env.sh
show() { python3 -c "
import json; d=json.load(open('$1')); md=d.get('multidevice')
line = 'image %.1f ms' % d['kernel_ms']
if md: line += '; split %s; ' % md['split'] + ', '.join('busy %.1f (kernels %.1f) finish %.1f setup %.1f' % (x['busy_ms'], x['kernel_ms'], x['finish_ms'], x['setup_ms']) for x in md['devices'])
print(line)"; }
same() { python3 tools/ppmdiff.py $1 $T/x.ppm | tail -1 | grep -q "same pixels" && echo "  same pixels" || echo "  PIXELS DIFFER from $1"; }
run() { # tag, binary, ranks, scene variable
  local second=""
  [ $3 = 2 ] && second=": -np 1 $G/$2 --mpi -p $P -d 1 ${!4} -q -o $T/x.ppm --stats $O/$1.json"
  mpirun --bind-to none -np 1 $G/$2 --mpi -p $P -d 0 ${!4} -q -o $T/x.ppm --stats $O/$1.json $second 2>&1 | grep rtcl
  echo "$4 MPI $2 $3 rank(s): $(show $O/$1.json)"; same $T/$4.ppm; }
for round in 1 2 3; do
  for b in rtcl-mpi-35c rtcl-mpi; do run D1-$b-$round $b 1 D; run D2-$b-$round $b 2 D; done
done
for round in 1 2; do
  for b in rtcl-mpi-35c rtcl-mpi; do run L1-$b-$round $b 1 L; run L2-$b-$round $b 2 L; done
  for b in rtcl-35c rtcl; do
    $G/$b -p $P -d 0 $L -q -o $T/x.ppm --stats $O/L-single-$b-$round.json
    echo "L one GPU, one render, $b: $(show $O/L-single-$b-$round.json)"; same $T/L.ppm
  done
done
for b in rtcl-35c rtcl; do
  $G/$b -p $P -d 0 $D -r 3 -q -o $T/x.ppm --stats $O/one-$b.json; echo "D one GPU -r 3 $b: $(show $O/one-$b.json)"; same $T/D.ppm
  $G/$b --devices $P:0,$P:1 $D -r 3 -q -o $T/x.ppm --stats $O/two-$b.json; echo "D two GPUs -r 3 $b: $(show $O/two-$b.json)"; same $T/D.ppm
done
tar czf $OUT/batch85-json.tgz -C $T json85
