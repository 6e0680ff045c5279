#!/bin/bash
# MPI against one process on this 2-core VM: before (spinning waits) and after
# (naps); image and frames; the overhead per piece from tiny frames.
set -u
cd /work/main
NEW=$PWD/rtcl; OLD=${OLD:-/tmp/ci/rtcl}
echo "commit: $(git rev-parse --short HEAD); old = $(git -C /tmp/ci rev-parse --short HEAD) (before the naps and the uncapped PoCL)"
grep -m1 "model name" /proc/cpuinfo; echo "load: $(cat /proc/loadavg)"
export OMPI_MCA_btl=self,vader,tcp OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 POCL_DEVICES="pthread pthread"
T=$(mktemp -d); mkdir -p $T/f
for b in ${BINS:-OLD NEW}; do
  R=${!b}
  echo "== $b: one 800x600 image at 4 spp (median of 3)"
  /usr/bin/python3 tools/multidevice_bench.py --rtcl $R --single 0:0 --multi 0:0,0:1 --mpi-np 2 --mpi-devices 0:0 --mpi-env POCL_DEVICES=pthread --size 800x600 --spp 4 --runs 3 --out $T/$b-image.md > /dev/null 2>&1
  grep -E "^\| (one|--devices 0:0,0:1 \(|mpirun)" $T/$b-image.md
  echo "== $b: 8 frames at 320x240"
  /usr/bin/python3 tools/multidevice_bench.py --rtcl $R --single 0:0 --multi 0:0,0:1 --mpi-np 2 --mpi-devices 0:0 --mpi-env POCL_DEVICES=pthread --frames 1:8 --size 320x240 --runs 3 --out $T/$b-frames.md > /dev/null 2>&1
  grep -E "^\| (one|--devices 0:0,0:1 \(|mpirun)" $T/$b-frames.md
done
echo "== overhead per piece: 200 frames of 8x8 (whole process, median of 3, ms)"
ms() { local s=$(date +%s%N); "$@" > /dev/null 2>&1; echo $(( ($(date +%s%N) - s) / 1000000 )); }
for b in ${BINS:-OLD NEW}; do
  R=${!b}
  for i in 1 2 3; do
    one=$(ms $R --devices 0:0,0:1 --frames 1:200 --size 8x8 -o $T/f/o.ppm)
    one1=$(ms $R --devices 0:0,0:1 --frames 1:1 --size 8x8 -o $T/f/o.ppm)
    mpi=$(ms mpirun --oversubscribe -np 2 -x POCL_DEVICES=pthread -x OMPI_MCA_btl $R --mpi --frames 1:200 --size 8x8 -o $T/f/o.ppm)
    mpi1=$(ms mpirun --oversubscribe -np 2 -x POCL_DEVICES=pthread -x OMPI_MCA_btl $R --mpi --frames 1:1 --size 8x8 -o $T/f/o.ppm)
    echo "  $b run $i: one process 2 devices: 200 frames $one ms, 1 frame $one1 ms; mpirun -np 2: 200 frames $mpi ms, 1 frame $mpi1 ms"
  done
done
echo "load: $(cat /proc/loadavg)"
