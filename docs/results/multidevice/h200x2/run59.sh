#!/bin/bash
# Issue 28, batch 59 (two H200s): batch 58's default-scene figures in one
# process again (its output file did not come back), and an experiment:
# RTCL_X_PASS_SAMPLES=1 makes every pass one sample of a piece's pixels.
# A piece of half the image otherwise takes two samples a pass (about 2^22
# pixel-samples a pass), and two halves cost 8 % more kernel time than the
# whole image (batch 54). Default scene 2000x2000 at 2048 spp, kernel dynamic,
# median of -r 3 after a warm-up, rounds interleaved; MPI: one whole run each.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run59.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'median %.1f ms (min %.1f, max %.1f), %d launches' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d['time_breakdown_ms']['launches'])
if md:
    line += '; ' + ', '.join('dev %d: %d pieces, %d px, busy %.1f, kernels %.1f in %d launches, finish %.1f' % (k,
        x['pieces'], x['pixels'], x['busy_ms'], x['kernel_ms'], x['launches'], x.get('finish_ms', 0))
        for k, x in enumerate(md['devices']))
    if 'pieces' in md: line += '; pieces ' + ', '.join('%.1f' % p['kernel_ms'] for p in md['pieces'])
    line += '; efficiency %.3f; %s' % (md['device_efficiency'], md['row_order'])
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical to one GPU's" || echo "  IMAGE DIFFERS"; }
mpi_run() { # tag, ranks, pass samples ('' for the default)
  local second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 --split static $D -q -o $T/mpi.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh; [ -n "$3" ] && export RTCL_X_PASS_SAMPLES=$3
    mpirun -np 1 $RM --mpi -p $P -d 0 --split static $D -q -o $T/mpi.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -v -E '^(output|time):|PMIx|pcompress|^----|^$' | tail -3
  echo "default MPI $2 rank(s), pass ${3:-default}: $(show $O/$1.json)"; same $T/one.ppm $T/mpi.ppm; }
for round in 1 2 3; do
  $R -p $P -d 0 $D -r 3 -q -o $T/one.ppm --stats $O/one-$round.json
  echo "default round $round one GPU: $(show $O/one-$round.json)"
  $R --devices $P:0,$P:1 $D -r 3 -q -o $T/two.ppm --stats $O/two-$round.json
  echo "default round $round two GPUs: $(show $O/two-$round.json)"; same $T/one.ppm $T/two.ppm
  RTCL_X_PASS_SAMPLES=1 $R --devices $P:0,$P:1 $D -r 3 -q -o $T/two1.ppm --stats $O/two1-$round.json
  echo "default round $round two GPUs, pass 1 sample: $(show $O/two1-$round.json)"; same $T/one.ppm $T/two1.ppm
  if [ $round = 1 ]; then
    for x in "" 1; do
      RTCL_X_PASS_SAMPLES=$x $R --devices $P:0 --piece-rows 1000 --row-order interleave:2 $D -r 3 -q \
        -o $T/halves.ppm --stats $O/halves$x.json
      echo "default halves on GPU 0, pass ${x:-default}: $(show $O/halves$x.json)"; same $T/one.ppm $T/halves.ppm
    done
  fi
done
for i in 1 2; do mpi_run mpi1-$i 1 ""; mpi_run mpi2-$i 2 ""; mpi_run mpi2p1-$i 2 1; done
$R -p $P -d 0 $L -r 3 -q -o $T/lone.ppm --stats $O/lake-one.json
echo "lake one GPU: $(show $O/lake-one.json)"
for x in "" 1; do
  RTCL_X_PASS_SAMPLES=$x $R --devices $P:0,$P:1 $L -r 3 -q -o $T/ltwo.ppm --stats $O/lake-two$x.json
  echo "lake two GPUs, pass ${x:-default}: $(show $O/lake-two$x.json)"; same $T/lone.ppm $T/ltwo.ppm
done
tar czf $OUT/batch59-json.tgz -C $T json
