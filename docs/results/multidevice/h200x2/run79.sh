#!/bin/bash
# Issue 28, batch 79 (two H200s), after run78.sh on the same machine: GPU +
# CPU against the float sums of 98ef897; the lake under MPI with Open MPI's
# default binding and with --bind-to none; MPI's transport alone (mpibw.c:
# 128 MB as one message or in chunks, rank 1 to rank 0).
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run79.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; B=$G/rtcl-base; RM=$G/rtcl-mpi
T=$(mktemp -d); O=$T/json79; mkdir -p $O
echo "commit: $COMMIT (base: 98ef897)"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
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
( . $G/ompi/env.sh
  for b in "" "--bind-to none"; do
    echo "mpibw, ${b:-default binding}:"; mpirun $b -np 2 $G/mpibw 128 | sort | uniq -c | sort -k2 | head -20
  done )
G1="-k dynamic --size 2000x2000 --spp 1024"
$R --devices $P:0,$C:0 $G1 --size 64x64 -q -o $T/prime.ppm  # PoCL's build
$B --devices $P:0,$C:0 $G1 --size 64x64 -q -o $T/prime.ppm
for X in $B $R; do
  $X -p $P -d 0 $G1 -r 3 -q -o $T/g.ppm --stats $O/gpu-$(basename $X).json
  echo "1024 spp GPU alone ($(basename $X)): $(show $O/gpu-$(basename $X).json)"
  $X --devices $P:0,$C:0 $G1 -r 3 -q -o $T/x.ppm --stats $O/gpucpu-$(basename $X).json
  echo "1024 spp GPU + CPU ($(basename $X)): $(show $O/gpucpu-$(basename $X).json)"; same $T/g.ppm $T/x.ppm
done
python3 tools/genbench.py lake -o $T/lake > /dev/null
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
$R -p $P -d 0 $L -q -o $T/L.ppm
mpi_run() { # tag, ranks, extra options, mpirun options
  local second=""
  [ $2 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 $L $3 -q -o $T/x.ppm --stats $O/$1.json"
  ( . $G/ompi/env.sh
    /usr/bin/time -f "process %e s" mpirun ${4:-} -np 1 $RM --mpi -p $P -d 0 $L $3 -q -o $T/x.ppm --stats $O/$1.json $second ) \
    2>&1 | grep -E '^process|rtcl' | tail -3
  echo "L MPI $2 rank(s) $3 ${4:-(default binding)}: $(show $O/$1.json)"; same $T/L.ppm $T/x.ppm; }
for b in "" "--bind-to none"; do
  n=${b:+n}; mpi_run mpi-L1$n 1 "" "$b"; mpi_run mpi-L2$n 2 "" "$b"; mpi_run mpi-L2s$n 2 "--split samples" "$b"
done
tar czf $OUT/batch79-json.tgz -C $T json79
