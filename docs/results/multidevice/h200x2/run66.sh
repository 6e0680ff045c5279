#!/bin/bash
# Issue 28, batch 66 (two H200s): which default? Queues 2, 3 or 4 with
# passes of the default size (about 2^22 pixel-samples) or of 4 samples
# (RTCL_X_PASS_SAMPLES, run64-experiment.patch), on one GPU and on two, on
# the default scene (2048 spp) and the lake (256 spp); one GPU rendering a
# GPU's half (every other 8-row band) by itself; and MPI (two ranks, one
# GPU each, against one rank) now that the bands are read back straight
# into place (73585e2). Binary: 73585e2 with the patch. -r 3 medians.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run66.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json66; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'kernels %.1f ms (min %.1f, max %.1f), wall %.1f, %d queues, %d passes' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), d.get('queues', 0), d.get('passes', 0))
if md:
    line += '; ' + ', '.join('dev %d: %d pieces, %d px, busy %.1f, kernels %.1f, finish %.1f' % (k,
        x['pieces'], x['pixels'], x['busy_ms'], x['kernel_ms'], x.get('finish_ms', 0))
        for k, x in enumerate(md['devices']))
    if 'pieces' in md and len(md['pieces']) < 6: line += '; pieces ' + ', '.join('%.1f' % p['kernel_ms'] for p in md['pieces'])
    line += '; efficiency %.3f' % md['device_efficiency']
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
$R -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm  # fills the program cache
$R -p $P -d 0 $L --size 64x64 -q -o $T/prime.ppm
one() { # tag, pass samples, args...
  local tag=$1 p=$2; shift 2
  RTCL_X_PASS_SAMPLES=$p $R "$@" -r 3 -q -o $T/x.ppm --stats $O/$tag.json
  echo "$tag (pass ${p:-default}): $(show $O/$tag.json)"; same $T/ref.ppm $T/x.ppm; }
for s in D L; do
  $R -p $P -d 0 ${!s} --queues 1 -q -o $T/ref.ppm
  for c in 2: 2:4 3:4 4:4; do
    q=${c%%:*}; p=${c#*:}
    one $s-one-q$q-p$p "$p" -p $P -d 0 ${!s} --queues $q
    one $s-two-q$q-p$p "$p" --devices $P:0,$P:1 ${!s} --queues $q
  done
  one $s-halves-q4-p4 4 --devices $P:0 --piece-rows 1000 --row-order interleave:2 ${!s} --queues 4
done
$R -p $P -d 0 $D --queues 1 -q -o $T/ref.ppm
mpi_run() { # tag, ranks, queues, pass samples
  local second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 --queues $3 $D -q -o $T/x.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh; export RTCL_X_PASS_SAMPLES=$4
    mpirun -np 1 $RM --mpi -p $P -d 0 --queues $3 $D -q -o $T/x.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -v -E '^(output|time):|PMIx|pcompress|zlib|comparable|compress|startup|^----|^$' | tail -3
  echo "default MPI $2 rank(s), $3 queues, pass ${4:-default}: $(show $O/$1.json)"; same $T/ref.ppm $T/x.ppm; }
for i in 1 2; do
  mpi_run mpi1-q2-$i 1 2 ""; mpi_run mpi2-q2-$i 2 2 ""
  mpi_run mpi1-q4p4-$i 1 4 4; mpi_run mpi2-q4p4-$i 2 4 4
done
tar czf $OUT/batch66-json.tgz -C $T json66
