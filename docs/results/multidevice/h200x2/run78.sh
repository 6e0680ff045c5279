#!/bin/bash
# Issue 28, batch 78 (two H200s; for the next session): the adopted form of
# the sums added in place (4 cl_long a pixel, saturation marks, 64-bit
# atomics) that batch 77 measured only as an experiment. One GPU against the
# float sums of 98ef897 (.gpu/rtcl-base) and against RTCL_BUILD_OPTIONS=
# -DRTCL_SUM_IN_REGISTERS (the pass's sum in registers); two GPUs split by
# samples; MPI one rank against two in bands; GPU + CPU. Default scene
# 2000x2000 at 2048 spp, the lake at 256 spp, kernel dynamic, -r 3, three
# interleaved rounds. MPI also with `mpirun --bind-to none`: Open MPI binds
# each of two ranks to one core by default, and rank 0 adds the sums or
# places the bands (8 threads) on that core. GPU + CPU, the lake under MPI
# and the transport alone (mpibw.c) are in run79.sh.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run78.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; B=$G/rtcl-base; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json78; mkdir -p $O
echo "commit: $COMMIT (base: 98ef897)"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice'); t = d.get('time_breakdown_ms', {})
line = 'kernels %.1f ms (min %.1f, max %.1f), wall %.1f, assemble %.1f ms' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), t.get('read_back', float('nan')))
if md:
    line += '; split %s%s; ' % (md['split'], ' (sums: %s)' % md['sums'] if 'sums' in md else '') + ', '.join('dev %d: %d px, busy %.1f, kernels %.1f, setup %.1f, finish %.1f' % (k,
        x['pixels'], x['busy_ms'], x['kernel_ms'], x['setup_ms'], x.get('finish_ms', 0)) for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f' % md['device_efficiency']
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
for s in D L; do
  for Y in $R $B; do $Y -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm; done  # program caches
  RTCL_BUILD_OPTIONS=-DRTCL_SUM_IN_REGISTERS $R -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm
  $R -p $P -d 0 ${!s} -q -o $T/$s.ppm
done
mpi_run() { # tag, ranks, scene variable, extra options, mpirun options
  local args="${!3} $4" second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 $args -q -o $T/x.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh
    /usr/bin/time -f "process %e s" mpirun ${5:-} -np 1 $RM --mpi -p $P -d 0 $args -q -o $T/x.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -E '^process|rtcl|bound' | tail -4
  echo "$3 MPI $2 rank(s) $4 ${5:-(default binding)}: $(show $O/$1.json)"; same $T/$3.ppm $T/x.ppm; }
for round in 1 2 3; do
  for s in D L; do
    $B -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-base-$round.json
    echo "$s one GPU, float sums (98ef897), round $round: $(show $O/$s-base-$round.json)"
    $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-one-$round.json
    echo "$s one GPU, round $round: $(show $O/$s-one-$round.json)"; same $T/$s.ppm $T/x.ppm
    RTCL_BUILD_OPTIONS=-DRTCL_SUM_IN_REGISTERS $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-reg-$round.json
    echo "$s one GPU, sums in registers, round $round: $(show $O/$s-reg-$round.json)"; same $T/$s.ppm $T/x.ppm
    $R --devices $P:0,$P:1 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-two-$round.json
    echo "$s two GPUs, round $round: $(show $O/$s-two-$round.json)"; same $T/$s.ppm $T/x.ppm
  done
  mpi_run mpi-D1-$round 1 D ""; mpi_run mpi-D2-$round 2 D ""
  mpi_run mpi-D1n-$round 1 D "" "--bind-to none"; mpi_run mpi-D2n-$round 2 D "" "--bind-to none"
  mpi_run mpi-D2s-$round 2 D "--split samples"
  mpi_run mpi-D2sn-$round 2 D "--split samples" "--bind-to none"
done
( . $G/ompi/env.sh; mpirun --report-bindings -np 2 $G/mpibw 1 2>&1 | grep bound
  mpirun --bind-to none --report-bindings -np 2 $G/mpibw 1 2>&1 | grep -i bound )
tar czf $OUT/batch78-json.tgz -C $T json78
