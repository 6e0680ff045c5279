#!/bin/bash
# Issue 28, batch 82 (two H200s): MPI after the page touches and the sums'
# own lock (6c72d03, with batch 81's RTCL_MPI_TRACE still in), Open
# MPI's single-copy mechanism (CMA, its default) against none (copies through
# shared memory), bands and --split samples, both bindings; one rank as the
# base. Default scene 2000x2000, 2048 spp, dynamic; two rounds.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run82.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi; T=$(mktemp -d); O=$T/json82; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
D="-k dynamic --size 2000x2000 --spp 2048"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm
$R -p $P -d 0 $D -q -o $T/D.ppm
. $G/ompi/env.sh
run() { # tag, ranks, options, mpirun options
  local second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 $D $3 -q -o $T/x.ppm --stats $O/$1.json"
  RTCL_MPI_TRACE=1 mpirun $4 -x RTCL_MPI_TRACE -np 1 $RM --mpi -p $P -d 0 $D $3 -q -o $T/x.ppm --stats $O/$1.json $second 2>&1 | grep trace | sort -k3 -n | awk 'NR==1{t0=$3} {printf "%s %9.1f %s\n", $2, $3-t0, substr($0, index($0,$4))}' > $O/$1.trace
  python3 -c "
import json; d=json.load(open('$O/$1.json')); md=d['multidevice']
print('$2 rank(s) $3 [$4]: image %.1f ms;' % d['kernel_ms'], ', '.join('busy %.1f finish %.1f' % (x['busy_ms'], x['finish_ms']) for x in md['devices']))"
  cmp -s $T/D.ppm $T/x.ppm || echo "  IMAGE DIFFERS"; }
for round in 1 2; do
  for m in cma none; do
    M="--mca btl_vader_single_copy_mechanism $m"
    run one-$m-$round 1 "" "--bind-to none $M"
    run bands-$m-$round 2 "" "--bind-to none $M"
    run samples-$m-$round 2 "--split samples" "--bind-to none $M"
    run samplesb-$m-$round 2 "--split samples" "$M"
  done
done
for f in $O/samples-*-1.trace; do echo "== $(basename $f)"; cat $f; done
tar czf $OUT/batch82-json.tgz -C $T json82
