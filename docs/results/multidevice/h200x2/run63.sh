#!/bin/bash
# Issue 28, batch 63 (two H200s): --queues, one device's pieces cut into
# column parts, each on its own in-order queue, launches alternating (batch
# 62: NVIDIA's OpenCL runs two queues' kernels at once), against one queue;
# and the adaptive split's tail rule kept for much slower devices only
# (batch 60's two GPUs took leftover slivers: 1188-1253 ms). Interleaved
# rounds, -r 3 medians (kernel_ms: the time any launch ran; frame_ms: wall).
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run63.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json63; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
python3 tools/genbench.py mount --size 8 -o $T/mount > /dev/null
M=$T/mount/spd-mount-8.json
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'kernels %.1f ms (min %.1f, max %.1f), wall %.1f, %d queues' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), d.get('queues', 0))
if md:
    line += '; ' + ', '.join('dev %d: %d pieces, %d px, busy %.1f, kernels %.1f, finish %.1f' % (k,
        x['pieces'], x['pixels'], x['busy_ms'], x['kernel_ms'], x.get('finish_ms', 0))
        for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f' % md['device_efficiency']
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm  # fills the program cache
$R -p $P -d 0 $L --size 64x64 -q -o $T/prime.ppm
for round in 1 2; do
  for q in 1 2; do
    $R -p $P -d 0 $D --queues $q -r 3 -q -o $T/d1-$q.ppm --stats $O/d1-q$q-$round.json
    echo "default one GPU, round $round: $(show $O/d1-q$q-$round.json)"; same $T/d1-1.ppm $T/d1-$q.ppm
    $R --devices $P:0,$P:1 $D --queues $q -r 3 -q -o $T/d2-$q.ppm --stats $O/d2-q$q-$round.json
    echo "default two GPUs, round $round: $(show $O/d2-q$q-$round.json)"; same $T/d1-1.ppm $T/d2-$q.ppm
  done
done
for q in 1 2; do
  $R -p $P -d 0 $L --queues $q -r 3 -q -o $T/l1-$q.ppm --stats $O/l1-q$q.json
  echo "lake one GPU: $(show $O/l1-q$q.json)"; same $T/l1-1.ppm $T/l1-$q.ppm
  $R --devices $P:0,$P:1 $L --queues $q -r 3 -q -o $T/l2-$q.ppm --stats $O/l2-q$q.json
  echo "lake two GPUs: $(show $O/l2-q$q.json)"; same $T/l1-1.ppm $T/l2-$q.ppm
done
for k in naive persistent cyclic; do
  for q in 1 2; do
    $R -p $P -d 0 -k $k --size 2000x2000 --spp 512 --queues $q -r 3 -q -o $T/k-$q.ppm --stats $O/k-$k-q$q.json
    echo "default 512 spp $k: $(show $O/k-$k-q$q.json)"; same $T/k-1.ppm $T/k-$q.ppm
  done
done
for k in persistent dynamic; do
  for q in 1 2; do
    $R -p $P -d 0 -k $k -s $M --size 2000x2000 --queues $q -r 10 -q -o $T/m-$q.ppm --stats $O/m-$k-q$q.json
    echo "mount 8 primary rays $k: $(show $O/m-$k-q$q.json)"; same $T/m-1.ppm $T/m-$q.ppm
  done
done
mpi_run() { # tag, queues
  ( . $G/ompi/env.sh
    mpirun -np 1 $RM --mpi -p $P -d 0 --queues $2 $D -q -o $T/mpi.ppm --stats $O/$1.json \
      : -np 1 $RM --mpi -p $P -d 1 --queues $2 $D -q -o $T/mpi.ppm --stats $O/$1.json ) \
    2>&1 | grep -v -E '^(output|time):|PMIx|pcompress|zlib|comparable|^----|^$' | tail -3
  echo "default MPI two ranks, $2 queues: $(show $O/$1.json)"; same $T/d1-1.ppm $T/mpi.ppm; }
for i in 1 2; do mpi_run mpi-q1-$i 1; mpi_run mpi-q2-$i 2; done
tar czf $OUT/batch63-json.tgz -C $T json63
