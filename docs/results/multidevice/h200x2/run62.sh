#!/bin/bash
# Issue 28, batch 62 (two H200s or H100s), run after run60.sh on the same
# machine: (1) whether NVIDIA's OpenCL runs two in-order queues' kernels at
# once (tools/device/queue_overlap.c; 132 groups of 256 fill an eighth of
# the GPU, so overlapping queues take about half the wall time; 1056 groups
# fill it, so only the launches' ends can overlap); (2) MPI, two ranks with
# one GPU each, at HEAD: the dynamic split now gives GPUs one band each
# (f7c730e) and rank 0 copies each band once (232b061), neither yet run on
# GPUs. Default scene 2000x2000, 2048 spp, kernel dynamic; one whole run
# each (MPI allows no -r).
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run62.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json62; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
cc -O2 -o $T/queue_overlap tools/device/queue_overlap.c -lOpenCL
for groups in 132 264 1056; do $T/queue_overlap $P 0 $groups 200000; done
$T/queue_overlap $P 0 1056 20000
D="-k dynamic --size 2000x2000 --spp 2048"
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'image %.1f ms' % d['kernel_ms']
if md:
    line += '; ' + ', '.join('dev %d: %d pieces, %d px, busy %.1f, kernels %.1f, finish %.1f' % (k,
        x['pieces'], x['pixels'], x['busy_ms'], x['kernel_ms'], x.get('finish_ms', 0))
        for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f' % md['device_efficiency']
print(line)" $1; }
$R -p $P -d 0 $D -q -o $T/one.ppm
mpi_run() { # tag, ranks, split
  local second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 --split $3 $D -q -o $T/mpi.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh
    /usr/bin/time -f "process %e s" mpirun -np 1 $RM --mpi -p $P -d 0 --split $3 $D -q -o $T/mpi.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -v -E '^(output|time):|PMIx|pcompress|^----|^$' | tail -3
  echo "default MPI $2 rank(s), $3: $(show $O/$1.json)"
  cmp -s $T/one.ppm $T/mpi.ppm && echo "  image identical to one GPU's" || echo "  IMAGE DIFFERS"; }
for i in 1 2 3; do mpi_run mpi1-$i 1 dynamic; mpi_run mpi2d-$i 2 dynamic; mpi_run mpi2s-$i 2 static; done
tar czf $OUT/batch62-json.tgz -C $T json62
