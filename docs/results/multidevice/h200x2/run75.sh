#!/bin/bash
# Issue 28, batch 75 (two H200s): MPI, two ranks of one GPU each on this
# node, split by samples with the sums in an MPI-3 window of shared memory
# that rank 0 now maps before the clock; Open MPI's backing file where it
# puts it, and in /dev/shm (OMPI_MCA_shmem_mmap_backing_file_base_dir).
# Default scene 2000x2000 at 2048 spp, kernel dynamic, one whole run each
# (image time), interleaved rounds.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run75.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json75; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L; nproc; df -h /tmp /dev/shm | tail -2
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'image %.1f ms' % d['kernel_ms']
if md:
    line += '; split %s%s; ' % (md['split'], ' (sums: %s)' % md['sums'] if 'sums' in md else '') + ', '.join('dev %d: busy %.1f, kernels %.1f, setup %.1f, finish %.1f' % (k,
        x['busy_ms'], x['kernel_ms'], x['setup_ms'], x.get('finish_ms', 0)) for k, x in enumerate(md['devices']))
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm
$R -p $P -d 0 $D -q -o $T/D.ppm
mpi_run() { # tag, ranks, extra environment
  local second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 $D -q -o $T/x.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh; [ -n "$3" ] && export $3
    /usr/bin/time -f "process %e s" mpirun -np 1 $RM --mpi -p $P -d 0 $D -q -o $T/x.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -E '^process|rtcl' | tail -3
  echo "MPI $2 rank(s) ${3:-}: $(show $O/$1.json)"; same $T/D.ppm $T/x.ppm; }
SHM=OMPI_MCA_shmem_mmap_backing_file_base_dir=/dev/shm
for round in 1 2 3; do
  mpi_run one-$round 1 ""
  mpi_run two-$round 2 ""
  mpi_run two-shm-$round 2 $SHM
done
tar czf $OUT/batch75-json.tgz -C $T json75
