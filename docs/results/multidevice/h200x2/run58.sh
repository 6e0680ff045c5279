#!/bin/bash
# Issue 28, batch 58: the first two-GPU machine lent since the interleaved
# split landed. One image over two GPUs against one, in one process
# (--devices) and as two MPI ranks with one GPU each, both row orders; the
# default scene at 2048 spp (about 1.8 s on one GPU: the issue asks for
# renders of >= 1 s) and the lake (2.1 M triangles) at 256 spp, 2000x2000,
# kernel dynamic. In-process figures are the median of -r 3 whole images after
# a warm-up; MPI allows no -r, so each MPI figure is one whole run
# (set-up included), three runs, against MPI with one rank and one GPU.
# GPU+CPU once, against batch 54's figures. Run with the binaries and the
# packed Open MPI in .gpu/ (tools/device/pack-openmpi.sh):
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run58.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; RM=$G/rtcl-mpi
O=${OUT:-$(mktemp -d)}
echo "commit: $COMMIT"; nvidia-smi -L; nproc
$R --list-devices
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
declare -A S=([default]="--size 2000x2000 --spp 2048" [lake]="-s $T/lake/lake-10.json --size 2000x2000 --spp 256")
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
line = 'median %.1f ms (min %.1f, max %.1f)' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'])
if md:
    line += '; ' + ', '.join('dev %d: %d pieces, %d px, busy %.1f, kernels %.1f, set-up %.1f, finish %.1f' % (k,
        x['pieces'], x['pixels'], x['busy_ms'], x['kernel_ms'], x.get('setup_ms', 0), x.get('finish_ms', 0))
        for k, x in enumerate(md['devices']))
    line += '; efficiency %.3f; %s' % (md['device_efficiency'], md['row_order'])
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical to one GPU's" || echo "  IMAGE DIFFERS"; }
mpi_run() { # scene, split, tag, ranks (1: GPU 0 alone; 2: GPU 0 and GPU 1)
  local second=""
  [ $4 = 2 ] && second=": -np 1 $RM --mpi -p $P -d 1 --split $2 -k dynamic ${S[$1]} -q -o $T/mpi-$1.ppm --stats $O/$3.json"
  ( . $G/ompi/env.sh
    mpirun -np 1 $RM --mpi -p $P -d 0 --split $2 -k dynamic ${S[$1]} -q -o $T/mpi-$1.ppm --stats $O/$3.json $second ) \
    2>&1 | grep -v -E '^(output|time):' | tail -3
  echo "$1 MPI $4 rank(s), --split $2: $(show $O/$3.json)"; same $T/one-$1.ppm $T/mpi-$1.ppm; }
for s in default lake; do
  for round in 1 2; do
    $R -p $P -d 0 -k dynamic ${S[$s]} -r 3 -q -o $T/one-$s.ppm --stats $O/one-$s-$round.json
    echo "$s round $round one GPU: $(show $O/one-$s-$round.json)"
    for o in interleave scan; do
      [ $o = scan ] && [ $round = 2 ] && continue
      $R --devices $P:0,$P:1 --row-order $o -k dynamic ${S[$s]} -r 3 -q -o $T/two-$s-$o.ppm \
        --stats $O/two-$s-$o-$round.json
      echo "$s round $round two GPUs, $o: $(show $O/two-$s-$o-$round.json)"
      same $T/one-$s.ppm $T/two-$s-$o.ppm
    done
    $R --devices $P:1 -k dynamic ${S[$s]} -r 3 -q -o $T/gpu1-$s.ppm --stats $O/gpu1-$s-$round.json
    echo "$s round $round the second GPU alone (--devices $P:1): $(show $O/gpu1-$s-$round.json)"
    for i in 1 2; do mpi_run $s static mpi1-$s-$round-$i 1; done
    for i in 1 2 3; do mpi_run $s static mpi-$s-static-$round-$i 2; done
    for i in 1 2; do mpi_run $s dynamic mpi-$s-dynamic-$round-$i 2; done
  done
  for i in 1 2; do
    TIMEFORMAT="$s one GPU, whole process: %R s"; time $R -p $P -d 0 -k dynamic ${S[$s]} -q -o $T/w.ppm
    TIMEFORMAT="$s two GPUs, whole process: %R s"; time $R --devices $P:0,$P:1 -k dynamic ${S[$s]} -q -o $T/w.ppm
    TIMEFORMAT="$s MPI two ranks, whole mpirun: %R s"; time mpi_run $s static mpi-$s-whole-$i 2 > /dev/null
  done
done
# GPU + CPU, default scene at 1024 spp (batch 54: 944-961 ms against one GPU's 922-927)
$R -p $P -d 0 -k dynamic --size 2000x2000 --spp 1024 -r 3 -q -o $T/g.ppm --stats $O/g1024.json
echo "default 1024 spp one GPU: $(show $O/g1024.json)"
$R --devices $P:0,$C:0 -k dynamic --size 2000x2000 --spp 1024 -r 3 -q -o $T/gc.ppm --stats $O/gc1024.json
echo "default 1024 spp GPU+CPU: $(show $O/gc1024.json)"; same $T/g.ppm $T/gc.ppm
$R --devices $P:0,$P:1,$C:0 -k dynamic --size 2000x2000 --spp 1024 -r 3 -q -o $T/ggc.ppm --stats $O/ggc1024.json
echo "default 1024 spp two GPUs + CPU: $(show $O/ggc1024.json)"; same $T/g.ppm $T/ggc.ppm
