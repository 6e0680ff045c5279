#!/bin/bash
# Issue 43, batch 98, second call (four H100s, nvidia-h100-x4), branch gpu4b
# at COMMIT (after the first call: the MPI sums' first device copied
# rather than added, blocking MPI_Barrier/MPI_Reduce once the ranks meet, and
# each rank's block of the shared sums mapped before the clock).
# The first call (run98.sh) lacked RTCL_MESHREAD, so its lake rows failed;
# this call gives the lake rows and, as its own baseline, the default
# scene's 1 and 4 GPU rows again. Two interleaved rounds:
#   one process, 1/2/4 GPUs (default scene 1/4), -r 3,
#   MPI, 1/2/4 ranks of one GPU each (mpirun --bind-to none), one render each,
# default scene 2000x2000 at 2048 spp and the lake (genbench.py lake) at 256
# spp, -k dynamic; every image compared with cmp against one GPU's. Then once:
# MPI 4 ranks with the sums by MPI_Reduce (RTCL_TEST_SUMS_BY_MESSAGES), and
# cf14357's MPI (.gpu/rtcl-mpi: rank 0 adding the sums serially; the lake in
# bands by the fixed threshold, and --split samples).
# Binaries: .gpu/gpu4b/b99/rtcl (make OIIO=0 MPI=0), .gpu/gpu4b/b99/rtcl-mpi (make OIIO=0).
#   COMMIT=<commit> bash .gpu/gpu4b/run98b.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; B=$G/gpu4b/b99; T=$(mktemp -d); O=$T/b98b; mkdir -p $O
exec > >(tee $OUT/run98b.txt) 2>&1
echo "commit: $COMMIT"; nvidia-smi -L; nproc; df -h /dev/shm | tail -1; date -u
P=$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ONE="-p $P -d 0"; TWO="--devices $P:0,$P:1"; FOUR="--devices $P:0,$P:1,$P:2,$P:3"
D="-k dynamic --size 2000x2000 --spp 2048"
python3 tools/genbench.py lake -o $T/lake > /dev/null
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
F="-k dynamic --size 2000x2000 --spp 256"
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice'); t = d['time_breakdown_ms']
f = d.get('frame_ms_all') or [d['kernel_ms']]
line = 'frame %.1f ms (median; all %s), read_back %.1f' % (d.get('frame_ms', d['kernel_ms']), ','.join('%.1f' % x for x in f), t['read_back'])
if md:
    line += '; split %s' % md['split']
    c = md.get('split_choice')
    if c: line += ' (measured: render %.1f, pass %.1f/%d, sums %.2f + add %.2f vs penalty %.2f)' % (c['render_ms'], c['pass_ms'], c['pass_samples'], c['sums_ms'], c['add_ms'], c['penalty_ms'])
    rs = md.get('rank_sums')
    if rs: line += '; rank sums by %s %.1f ms' % (rs['added_by'], rs['ms'])
    line += '; eff %.3f; ' % md['device_efficiency'] + ', '.join('busy %.1f kern %.1f fin %.1f' % (x['busy_ms'], x['kernel_ms'], x['finish_ms']) for x in md['devices'])
print(line)" $1 2>&1; }
same() { cmp -s $1 $2 && echo "  same bytes as $(basename $1)" || echo "  IMAGE DIFFERS from $(basename $1)"; }
r() { # tag, devices, scene variable, extra options
  local tag=$1 devs=$2 sc=$3; shift 3
  $B/rtcl ${!devs} ${!sc} -r 3 -q -o $T/$tag.ppm --stats $O/$tag.json "$@" 2>&1 | head -5
  echo "$tag: $(show $O/$tag.json)"; }
. $G/ompi/env.sh
m() { # tag, binary, ranks, scene variable, extra options
  local tag=$1 b=$2 n=$3 sc=$4; shift 4; local cmd="" i
  for ((i = 0; i < n; i++)); do cmd+="${cmd:+ : }-np 1 $b --mpi -p $P -d $i ${!sc} -q -o $T/$tag.ppm --stats $O/$tag.json $*"; done
  local s=$(date +%s.%N); mpirun --bind-to none $cmd 2>&1 | head -5; local e=$(date +%s.%N)
  echo "$tag: $(show $O/$tag.json); mpirun $(python3 -c "print('%.0f ms' % (($e - $s) * 1e3))")"; same $T/$sc-1-1.ppm $T/$tag.ppm; }
fr() { # tag, binary, devices, last frame
  mkdir -p $T/$1
  $2 ${!3} $F --frames 0:$4 -q -o $T/$1/f.ppm --stats $O/$1.json 2>&1 | head -3
  python3 -c "import json; d=json.load(open('$O/$1.json')); md=d.get('multidevice') or {}
print('$1: wall %.1f ms;' % d['wall_ms'], '; '.join('%d frames busy %.1f kern %.1f fin %.1f' % (x['pieces'], x['busy_ms'], x['kernel_ms'], x['finish_ms']) for x in md.get('devices', [])), '; eff %.3f' % md.get('device_efficiency', 1))" 2>&1; }
for sc in D L; do $B/rtcl $ONE ${!sc} --spp 4 -q -o $T/prime.ppm; done
for round in 1 2; do
  for sc in D L; do
    echo "== round $round, $sc: one process, -r 3"
    r $sc-1-$round ONE $sc
    [ $sc = L ] && { r $sc-2-$round TWO $sc; same $T/$sc-1-1.ppm $T/$sc-2-$round.ppm; }
    r $sc-4-$round FOUR $sc; same $T/$sc-1-1.ppm $T/$sc-4-$round.ppm
    echo "== round $round, $sc: MPI, 1, 2, 4 ranks of one GPU, unbound, one render each"
    for n in 1 2 4; do m m$sc$n-$round $B/rtcl-mpi $n $sc; done
  done
done
echo "== once: MPI 4 ranks, sums by MPI_Reduce; cf14357's MPI on 4 ranks"
export RTCL_TEST_SUMS_BY_MESSAGES=1
m mD4-reduce $B/rtcl-mpi 4 D; m mL4-reduce $B/rtcl-mpi 4 L
m mD4-reduce-sam $B/rtcl-mpi 4 D --split samples
unset RTCL_TEST_SUMS_BY_MESSAGES
m mL4-sam $B/rtcl-mpi 4 L --split samples
export RTCL_TEST_SUMS_BY_MESSAGES=1
unset RTCL_TEST_SUMS_BY_MESSAGES
m mD4-old $G/rtcl-mpi 4 D; m mL4-old $G/rtcl-mpi 4 L; m mL4-old-sam $G/rtcl-mpi 4 L --split samples
tar czf $OUT/batch98b-json.tgz -C $T b98b; date -u
