#!/bin/bash
# Issue 28, batch 69 (two H200s): batch 67's defaults again with GPU passes
# of at least 4 samples (8b620ad): 2 queues for a whole image, 4 for a
# GPU's share, the adaptive split's rate-weighted floor, MPI bands read
# straight into place; three interleaved rounds of -r 3; MPI (one whole run
# each, image time); GPU + CPU against the GPU alone. Default scene
# 2000x2000 at 2048 spp, the lake at 256 spp, kernel dynamic.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run69.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json69; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
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
$R -p $P -d 0 $D --queues 1 -q -o $T/D.ppm
$R -p $P -d 0 $L --queues 1 -q -o $T/L.ppm
for round in 1 2 3; do
  for s in D L; do
    $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-one-$round.json
    echo "$s one GPU, round $round: $(show $O/$s-one-$round.json)"; same $T/$s.ppm $T/x.ppm
    $R --devices $P:0,$P:1 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-two-$round.json
    echo "$s two GPUs, round $round: $(show $O/$s-two-$round.json)"; same $T/$s.ppm $T/x.ppm
  done
done
mpi_run() { # tag, ranks, scene variable
  local args=${!3} second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 $args -q -o $T/x.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh
    /usr/bin/time -f "process %e s" mpirun -np 1 $RM --mpi -p $P -d 0 $args -q -o $T/x.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -E '^process|rtcl' | tail -3
  echo "$3 MPI $2 rank(s): $(show $O/$1.json)"; same $T/$3.ppm $T/x.ppm; }
for i in 1 2; do mpi_run mpi-D1-$i 1 D; mpi_run mpi-D2-$i 2 D; done
G1="-k dynamic --size 2000x2000 --spp 1024"
$R --devices $P:0,$C:0 $G1 --size 64x64 -q -o $T/prime.ppm  # PoCL's build
for q in ""; do
  Q=${q:+--queues $q}
  $R -p $P -d 0 $G1 $Q -r 3 -q -o $T/g.ppm --stats $O/gpu-q$q.json
  echo "1024 spp GPU alone ${q:+(--queues $q)}: $(show $O/gpu-q$q.json)"
  $R --devices $P:0,$C:0 $G1 $Q -r 3 -q -o $T/x.ppm --stats $O/gpucpu-q$q.json
  echo "1024 spp GPU + CPU ${q:+(--queues $q)}: $(show $O/gpucpu-q$q.json)"; same $T/g.ppm $T/x.ppm
done
tar czf $OUT/batch69-json.tgz -C $T json69
