#!/bin/bash
# Issue 28, batch 73 (two H200s), dd8373f: where one GPU's 0.8 % with the
# fixed-point sums goes, and MPI with the sums sent as they lie. One GPU:
# float sums (98ef897, .gpu/rtcl-base) against the fixed point summed per
# pass (the default), per sample (RTCL_BUILD_OPTIONS=-DRTCL_SUM_PER_SAMPLE),
# and under a register cap of 88 instead of 80; NVIDIA's register and spill
# report for each (-cl-nv-verbose). MPI: one rank against two (samples, the
# default; and --split dynamic). Default scene 2000x2000 at 2048 spp, the
# lake at 256 spp, kernel dynamic, -r 3, two interleaved rounds.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run73.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; B=$G/rtcl-base; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json73; mkdir -p $O
echo "commit: $COMMIT (base: 98ef897)"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice'); t = d.get('time_breakdown_ms', {})
line = 'kernels %.1f ms (min %.1f, max %.1f), wall %.1f, %d passes, assemble %.1f ms' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), d.get('passes', 0), t.get('read_back', float('nan')))
if md:
    line += '; split %s; ' % md['split'] + ', '.join('dev %d: %d px, busy %.1f, kernels %.1f, setup %.1f, finish %.1f' % (k,
        x['pixels'], x['busy_ms'], x['kernel_ms'], x['setup_ms'], x.get('finish_ms', 0)) for k, x in enumerate(md['devices']))
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
V=("" "-DRTCL_SUM_PER_SAMPLE" "-cl-nv-maxrregcount=88")
N=(pass sample cap88)
for s in D L; do
  echo "== $s register reports (-cl-nv-verbose, fresh builds)"
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $B -v -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm 2>&1 | grep -iE "registers|spill" | sed 's/^/  float: /' | head -4
  for i in 0 1 2; do
    RTCL_CACHE=0 RTCL_BUILD_OPTIONS="-cl-nv-verbose ${V[$i]}" $R -v -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm 2>&1 | grep -iE "registers|spill" | sed "s/^/  ${N[$i]}: /" | head -4
    RTCL_BUILD_OPTIONS="${V[$i]}" $R -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm  # the cache
  done
  $B -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm
  $R -p $P -d 0 ${!s} -q -o $T/$s.ppm
done
for round in 1 2; do
  for s in D L; do
    $B -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-base-$round.json
    echo "$s one GPU, float sums (98ef897), round $round: $(show $O/$s-base-$round.json)"
    for i in 0 1 2; do
      RTCL_BUILD_OPTIONS="${V[$i]}" $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-${N[$i]}-$round.json
      echo "$s one GPU, fixed point (${N[$i]}), round $round: $(show $O/$s-${N[$i]}-$round.json)"; same $T/$s.ppm $T/x.ppm
    done
  done
done
mpi_run() { # tag, ranks, scene variable, extra options
  local args="${!3} $4" second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 $args -q -o $T/x.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh
    /usr/bin/time -f "process %e s" mpirun -np 1 $RM --mpi -p $P -d 0 $args -q -o $T/x.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -E '^process|rtcl' | tail -3
  echo "$3 MPI $2 rank(s) $4: $(show $O/$1.json)"; same $T/$3.ppm $T/x.ppm; }
for i in 1 2; do
  mpi_run mpi-D1-$i 1 D ""; mpi_run mpi-D2-$i 2 D ""; mpi_run mpi-D2dyn-$i 2 D "--split dynamic"
done
mpi_run mpi-L2 2 L ""
tar czf $OUT/batch73-json.tgz -C $T json73
