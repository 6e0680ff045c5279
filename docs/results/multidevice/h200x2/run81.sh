#!/bin/bash
# Issue 28, batch 81 (two H200s): the timeline of the sums' and bands' way to
# rank 0 under MPI, printed by the experiment e01c2a3 (RTCL_MPI_TRACE, since
# taken out): CLOCK_MONOTONIC in ms, shared by the ranks of one machine.
#   COMMIT=e01c2a3 bash docs/results/multidevice/h200x2/run81.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi; T=$(mktemp -d)
echo "commit: $COMMIT"
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
D="-k dynamic --size 2000x2000 --spp 2048"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm
. $G/ompi/env.sh
for opt in "--split samples" "" "--split samples" ""; do
  echo "== MPI --bind-to none $opt"
  RTCL_MPI_TRACE=1 mpirun --bind-to none -x RTCL_MPI_TRACE -np 1 $RM --mpi -p $P -d 0 $D $opt -q -o $T/x.ppm --stats $T/s.json : -np 1 $RM --mpi -p $P -d 1 $D $opt -q -o $T/x.ppm --stats $T/s.json 2>&1 | grep trace | sort -k3 -n | awk 'NR==1{t0=$3} {printf "%s %9.1f %s\n", $2, $3-t0, substr($0, index($0,$4))}'
  python3 -c "import json; d=json.load(open('$T/s.json')); print('image', d['kernel_ms'], [(x['busy_ms'], x['finish_ms']) for x in d['multidevice']['devices']])"
done
