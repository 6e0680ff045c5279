#!/bin/bash
# Issue 28, batch 80 (two H200s): MPI with the read-backs into page-aligned
# host memory (461306b) against 89ccbe5 (.gpu/rtcl-mpi-89c), whose sample
# sums lay 8 bytes past a 16-byte boundary; Open MPI's default binding and
# --bind-to none; bands and --split samples; two GPUs in one process as a
# check. Default scene 2000x2000 at 2048 spp, kernel dynamic, three
# interleaved rounds; then the lake (256 spp) under MPI once.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run80.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; NEW=$G/rtcl-mpi; OLD=$G/rtcl-mpi-89c
T=$(mktemp -d); O=$T/json80; mkdir -p $O
echo "commit: $COMMIT (old: 89ccbe5)"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'image %.1f ms' % d['kernel_ms']
if md:
    line += '; split %s; ' % md['split'] + ', '.join('dev %d: busy %.1f, kernels %.1f, finish %.1f' % (k,
        x['busy_ms'], x['kernel_ms'], x.get('finish_ms', 0)) for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f' % md['device_efficiency']
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
python3 tools/genbench.py lake -o $T/lake > /dev/null
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm
$R -p $P -d 0 $D -q -o $T/D.ppm
$R -p $P -d 0 $L -q -o $T/L.ppm
mpi_run() { # tag, binary, ranks, scene variable, extra options, mpirun options
  local args="${!4} $5" second=""
  [ $3 = 2 ] && second=": -np 1 $2 --mpi -p $P -d 1 $args -q -o $T/x.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh
    mpirun ${6:-} -np 1 $2 --mpi -p $P -d 0 $args -q -o $T/x.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -E 'rtcl' | tail -3
  echo "$4 MPI $(basename $2) $3 rank(s) $5 ${6:-(default binding)}: $(show $O/$1.json)"; same $T/$4.ppm $T/x.ppm; }
for round in 1 2 3; do
  for b in "" "--bind-to none"; do
    n=${b:+n}
    mpi_run D1$n-$round $NEW 1 D "" "$b"
    for X in $OLD $NEW; do
      x=$(basename $X)
      mpi_run D2$n-$x-$round $X 2 D "" "$b"
      mpi_run D2s$n-$x-$round $X 2 D "--split samples" "$b"
    done
  done
  $R -p $P -d 0 $D -r 3 -q -o $T/x.ppm --stats $O/one-$round.json
  echo "D one GPU, round $round: $(show $O/one-$round.json)"; same $T/D.ppm $T/x.ppm
  $R --devices $P:0,$P:1 $D -r 3 -q -o $T/x.ppm --stats $O/two-$round.json
  echo "D two GPUs, round $round: $(show $O/two-$round.json)"; same $T/D.ppm $T/x.ppm
done
for X in $OLD $NEW; do
  mpi_run L2sn-$(basename $X) $X 2 L "--split samples" "--bind-to none"
done
mpi_run L1n $NEW 1 L "" "--bind-to none"; mpi_run L2n $NEW 2 L "" "--bind-to none"
tar czf $OUT/batch80-json.tgz -C $T json80
