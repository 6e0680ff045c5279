#!/bin/bash
# Issue 28, batch 71 (two H200s), 536c144: one GPU with the fixed-point sums
# loaded after a pass's samples against the float sums of 98ef897
# (.gpu/rtcl-base); two GPUs split by samples (the default) with the sums
# added by 8 threads and no float images read back; MPI, one rank against
# two (split by samples by default); the default's threshold at 256 and
# 512 spp. Default scene 2000x2000 at 2048 spp, the lake at 256 spp, kernel
# dynamic, -r 3, interleaved rounds.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run71.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; B=$G/rtcl-base; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json71; mkdir -p $O
echo "commit: $COMMIT (base: 98ef897)"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice'); t = d.get('time_breakdown_ms', {})
line = 'kernels %.1f ms (min %.1f, max %.1f), wall %.1f, %d queues, assemble %.1f ms, process %.0f ms' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), d.get('queues', 0), t.get('read_back', float('nan')), t.get('total', float('nan')))
if md:
    line += '; split %s; ' % md['split'] + ', '.join('dev %d: %d pieces, %d px, busy %.1f, kernels %.1f, finish %.1f' % (k,
        x['pieces'], x['pixels'], x['busy_ms'], x['kernel_ms'], x.get('finish_ms', 0))
        for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f' % md['device_efficiency']
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
for X in $R $B; do
  $X -p $P -d 0 $D --size 64x64 -q -o $T/prime.ppm  # fills the program caches
  $X -p $P -d 0 $L --size 64x64 -q -o $T/prime.ppm
done
$R -p $P -d 0 $D -q -o $T/D.ppm
$R -p $P -d 0 $L -q -o $T/L.ppm
for round in 1 2; do
  for s in D L; do
    $B -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-base-$round.json
    echo "$s one GPU, float sums (98ef897), round $round: $(show $O/$s-base-$round.json)"
    $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-one-$round.json
    echo "$s one GPU, round $round: $(show $O/$s-one-$round.json)"; same $T/$s.ppm $T/x.ppm
    $R --devices $P:0,$P:1 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-samples-$round.json
    echo "$s two GPUs, default (samples), round $round: $(show $O/$s-samples-$round.json)"; same $T/$s.ppm $T/x.ppm
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
mpi_run mpi-L1 1 L; mpi_run mpi-L2 2 L
for spp in 256 512; do
  S="-k dynamic --size 2000x2000 --spp $spp"
  $R -p $P -d 0 $S -r 5 -q -o $T/s.ppm --stats $O/short$spp-one.json
  echo "$spp spp one GPU: $(show $O/short$spp-one.json)"
  for sp in samples dynamic; do
    $R --devices $P:0,$P:1 $S --split $sp -r 5 -q -o $T/x.ppm --stats $O/short$spp-$sp.json
    echo "$spp spp two GPUs --split $sp: $(show $O/short$spp-$sp.json)"; same $T/s.ppm $T/x.ppm
  done
done
tar czf $OUT/batch71-json.tgz -C $T json71
