#!/bin/bash
# Issue 28, batch 83 (two H200s): MPI at the defaults of the final code (the
# sample split unless a rank is bound to one core), one rank against two,
# unbound (--bind-to none) and with Open MPI's default binding; two GPUs in
# one process beside. Default scene 2000x2000 at 2048 spp and the lake at
# 256 spp, kernel dynamic, three interleaved rounds (the lake's MPI runs once:
# each rank builds the BVH).
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run83.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi; T=$(mktemp -d); O=$T/json83; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
D="-k dynamic --size 2000x2000 --spp 2048"
python3 tools/genbench.py lake -o $T/lake > /dev/null
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm
$R -p $P -d 0 $D -q -o $T/D.ppm
$R -p $P -d 0 $L -q -o $T/L.ppm
. $G/ompi/env.sh
show() { python3 -c "
import json; d=json.load(open('$1')); md=d['multidevice']
print('image %.1f ms; split %s;' % (d['kernel_ms'], md['split']), ', '.join('busy %.1f (kernels %.1f) finish %.1f' % (x['busy_ms'], x['kernel_ms'], x['finish_ms']) for x in md['devices']))"; }
run() { # tag, ranks, scene variable, mpirun options
  local second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 ${!3} -o $T/x.ppm --stats $O/$1.json"
  mpirun $4 -np 1 $RM --mpi -p $P -d 0 ${!3} -o $T/x.ppm --stats $O/$1.json $second 2>&1 | grep "rtcl: note" | cut -c1-60
  echo "$3 MPI $2 rank(s) [${4:-default binding}]: $(show $O/$1.json)"
  cmp -s $T/$3.ppm $T/x.ppm || echo "  IMAGE DIFFERS"; }
for round in 1 2 3; do
  run D1n-$round 1 D "--bind-to none"
  run D2n-$round 2 D "--bind-to none"
  run D1-$round 1 D ""
  run D2-$round 2 D ""
  $R --devices $P:0,$P:1 $D -r 3 -q -o $T/x.ppm --stats $O/two-$round.json
  echo "D two GPUs in one process: $(show $O/two-$round.json)"
  cmp -s $T/D.ppm $T/x.ppm || echo "  IMAGE DIFFERS"
done
run L1n 1 L "--bind-to none"; run L2n 2 L "--bind-to none"
tar czf $OUT/batch83-json.tgz -C $T json83
