#!/bin/bash
# Issue 43, batch 102 (branch mpiwin at COMMIT): the path-traced Cornell box
# (scenes/cornell.json, 2048x2048, 64 spp, -k dynamic) over 1 and 4 MPI
# ranks of one GPU each (nvidia-h100-x4), the 4 ranks' sample split run
# each of the three ways RTCL_MPI_SUMS names for a rank's sums to reach its
# slot of the node's shared window, two interleaved rounds:
#   copy      (the default, batch 100's way) the device's sums read back
#             into pinned memory in 8 parts, each copied into the slot:
#             4 x 134 MB copied at once, the frame 10-12 ms after the devices
#   host-ptr  a CL_MEM_USE_HOST_PTR buffer made on the slot before the
#             clock; the sums copied into it on the device and mapped for
#             reading: no host copy, fast if NVIDIA's OpenCL pins the slot
#   read      clEnqueueReadBuffer straight into the slot (unpinned: a
#             staging copy in the driver, expected slower)
# Every image compared with cmp against one rank's (round 1). The lines
# give frame_ms (rank 0's clock to every rank's sums in its slot), the
# ranks' add after it, the way that ran (rank_sums.into_slot; a way that
# could not be set up falls back to copy) and each device's busy, finish
# and set-up times (set-up: before the clock, host-ptr's buffer on the slot
# included). Issue 43 wants 4 ranks >= 3.7x one rank (batch 100:
# 3.65-3.68x).
# About 40-60 s of commands (batch 100's MPI rows of C took 2-5 s each).
#
# Binary (built on the VM, carried in .gpu/mpiwin/, or the folder B names):
#   make OIIO=0 BUILD=build-gpu-mpi BIN=.gpu/mpiwin/rtcl-mpi
# with .gpu/lib (libjansson, ocl-icd) and .gpu/ompi (Open MPI 4.1,
# tools/device/pack-openmpi.sh) beside it. On the device, from the
# repository root, carrying .gpu/mpiwin, .gpu/lib and .gpu/ompi:
#   COMMIT=<commit> bash docs/results/h100x4/run102.sh
# (raw output $OUT/run102.txt, --stats files in $OUT/batch102-json.tgz).
# Without an NVIDIA platform (a dry run on PoCL: OUT=/tmp/x bash run102.sh)
# it renders a tiny image on four PoCL CPU devices taken as GPUs instead.
set -u
G=$PWD/.gpu; B=${B:-$G/mpiwin}; T=$(mktemp -d); O=$T/b102; mkdir -p $O
OUT=${OUT:-$(mktemp -d)}; mkdir -p $OUT
if command -v nvidia-smi > /dev/null; then
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
  export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$G/lib:${LD_LIBRARY_PATH:-}
fi
exec > >(tee $OUT/run102.txt) 2>&1
echo "commit: ${COMMIT:-unknown}"; nvidia-smi -L 2> /dev/null; nproc; date -u
P=$($B/rtcl-mpi --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
if [ -n "$P" ]; then
  DRY=0
  C="-k dynamic -s scenes/cornell.json --size 2048x2048 --spp 64"
else
  # Dry run: four PoCL CPU devices, taken as GPUs (the GPUs' choices), tiny.
  echo "no NVIDIA platform: a dry run on PoCL"
  DRY=1; P=0
  export POCL_DEVICES="pthread pthread pthread pthread" RTCL_TEST_AS_GPUS=1
  C="-k dynamic -s scenes/cornell.json --size 48x32 --spp 8"
fi
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice'); fr = d.get('frame_ms', d['kernel_ms'])
line = 'frame %.1f ms' % fr
if md:
    line += '; split %s' % md['split']
    c = md.get('split_choice')
    if c: line += ' (measured: sums %.2f + add %.2f vs penalty %.2f)' % (c['sums_ms'], c['add_ms'], c['penalty_ms'])
    rs = md.get('rank_sums')
    if rs: line += '; sums into the slot by %s, add after the frame %.1f ms (frame + add %.1f)' % (rs.get('into_slot', '?'), rs['ms'], fr + rs['ms'])
    line += '; eff %.3f; ' % md['device_efficiency'] + ', '.join('busy %.1f fin %.1f setup %.1f' % (x['busy_ms'], x['finish_ms'], x['setup_ms']) for x in md['devices'])
print(line)" $1 2>&1; }
same() { cmp -s $1 $2 && echo "  same bytes as $(basename $1)" || echo "  IMAGE DIFFERS from $(basename $1)"; }
if [ -f $G/ompi/env.sh ]; then . $G/ompi/env.sh; fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 # the device runs as root
MPIRUN="mpirun --bind-to none"; [ $DRY = 1 ] && MPIRUN="$MPIRUN --oversubscribe"
m() { # tag, ranks, way (RTCL_MPI_SUMS)
  local tag=$1 n=$2 way=$3 cmd="" i
  for ((i = 0; i < n; i++)); do cmd+="${cmd:+ : }-np 1 $B/rtcl-mpi --mpi -p $P -d $i $C -q -o $T/$tag.ppm --stats $O/$tag.json"; done
  local s=$(date +%s.%N); RTCL_MPI_SUMS=$way $MPIRUN -x RTCL_MPI_SUMS $cmd 2>&1 | grep -v -e PMIx -e 'compression library' -e 'system. We will' -e 'large data streams' -e 'startup times' -e '^----' | head -5; local e=$(date +%s.%N)
  echo "$tag: $(show $O/$tag.json); mpirun $(python3 -c "print('%.0f ms' % (($e - $s) * 1e3))")"; [ -f $T/m1-1.ppm ] && [ $tag != m1-1 ] && same $T/m1-1.ppm $T/$tag.ppm; }
$B/rtcl-mpi -p $P -d 0 $C --spp 4 --size 64x64 -q -o $T/prime.ppm # the program cache
for round in 1 2; do
  echo "== round $round: MPI, 1 rank, then 4 ranks of one GPU each by copy, host-ptr, read"
  m m1-$round 1 copy
  for way in copy host-ptr read; do m m4-$way-$round 4 $way; done
done
python3 -c "
import json, sys
one = [json.load(open('$O/m1-%d.json' % r))['frame_ms'] for r in (1, 2)]
print('1 rank: %.1f, %.1f ms' % tuple(one))
for way in ('copy', 'host-ptr', 'read'):
    f = [json.load(open('$O/m4-%s-%d.json' % (way, r))) for r in (1, 2)]
    ms = [d['frame_ms'] for d in f]; add = [d['multidevice']['rank_sums']['ms'] for d in f]
    print('4 ranks, %-8s: %.1f, %.1f ms (%.2fx, %.2fx one rank; with the add %.2fx, %.2fx)' % (way, ms[0], ms[1], one[0] / ms[0], one[1] / ms[1], one[0] / (ms[0] + add[0]), one[1] / (ms[1] + add[1])))
" 2>&1
same $T/m1-1.ppm $T/m1-2.ppm
tar czf $OUT/batch102-json.tgz -C $T b102; date -u
rm -rf $T
