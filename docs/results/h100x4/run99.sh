#!/bin/bash
# Issue 43, batch 99 (branch gpu43 at COMMIT): one image over 1, 2 and 4 GPUs
# of one host (nvidia-h100-x4), in one process and over MPI ranks of one GPU
# each, for the default scene (2000x2000, 2048 spp), the lake (2000x2000, 256
# spp, 2.1 M triangles) and the path-traced Cornell box (scenes/cornell.json,
# -k dynamic 2048x2048 64 spp, about 440 ms on one H100 (batch 98: 109 ms at
# 1024x1024); and -k wavefront 2048x2048 64 spp, about 300 ms), two interleaved rounds; then --frames 0:15
# and 0:5 of the default scene's orbit (2000x2000, 256 spp) on 1 and 4 GPUs.
# Every image is compared with cmp against one GPU's (round 1, one process).
# Under --mpi the image time now ends once every rank's sums are in the
# node's shared memory and the ranks' add is timed apart (rank_sums), as one
# process's frame ends with its devices' sums on the host and its add comes
# after; the lines print both and their total. About 280 s of commands.
#
# Binaries (built on the VM, carried in .gpu/gpu43/, or the folder B names):
#   make OIIO=0 MPI=0 BUILD=build-gpu BIN=.gpu/gpu43/rtcl
#   cp build-gpu/rtcl-meshread .gpu/gpu43/
#   make OIIO=0 BUILD=build-gpu-mpi BIN=.gpu/gpu43/rtcl-mpi
# with .gpu/lib (libjansson, ocl-icd, assimp) and .gpu/ompi (Open MPI 4.1,
# tools/device/pack-openmpi.sh) beside them. On the device, from the
# repository root, carrying .gpu/gpu43, .gpu/lib and .gpu/ompi:
#   COMMIT=<commit> bash docs/results/h100x4/run99.sh
# Without an NVIDIA platform (a dry run on PoCL: OUT=/tmp/x bash run99.sh) it
# renders tiny images on four PoCL CPU devices taken as GPUs instead.
set -u
G=$PWD/.gpu; B=${B:-$G/gpu43}; T=$(mktemp -d); O=$T/b99; mkdir -p $O
OUT=${OUT:-$(mktemp -d)}; mkdir -p $OUT
if command -v nvidia-smi > /dev/null; then
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
  export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$G/lib:${LD_LIBRARY_PATH:-}
fi
export RTCL_MESHREAD=$B/rtcl-meshread
exec > >(tee $OUT/run99.txt) 2>&1
echo "commit: ${COMMIT:-unknown}"; nvidia-smi -L 2> /dev/null; nproc; date -u
P=$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
if [ -n "$P" ]; then
  DRY=0; LAKE_SIZE=10
  D="-k dynamic --size 2000x2000 --spp 2048"
  LS="-k dynamic --size 2000x2000 --spp 256"
  C="-k dynamic -s scenes/cornell.json --size 2048x2048 --spp 64"
  W="-k wavefront -s scenes/cornell.json --size 2048x2048 --spp 64"
  F="-k dynamic --size 2000x2000 --spp 256"
else
  # Dry run: four PoCL CPU devices, taken as GPUs (the GPUs' choices), tiny.
  echo "no NVIDIA platform: a dry run on PoCL"
  DRY=1; P=0; LAKE_SIZE=6
  export POCL_DEVICES="pthread pthread pthread pthread" RTCL_TEST_AS_GPUS=1
  D="-k dynamic --size 48x32 --spp 16"
  LS="-k dynamic --size 48x32 --spp 8"
  C="-k dynamic -s scenes/cornell.json --size 48x32 --spp 8"
  W="-k wavefront -s scenes/cornell.json --size 48x32 --spp 8"
  F="-k dynamic --size 48x32 --spp 4"
fi
ONE="-p $P -d 0"; TWO="--devices $P:0,$P:1"; FOUR="--devices $P:0,$P:1,$P:2,$P:3"
python3 tools/genbench.py lake --size $LAKE_SIZE -o $T/lake > /dev/null || echo "genbench lake FAILED"
L="-s $(ls $T/lake/lake-*.json | head -1) $LS"
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
    if rs: line += '; rank sums by %s, add after the frame %.1f ms (frame + add %.1f)' % (rs['added_by'], rs['ms'], d.get('frame_ms', d['kernel_ms']) + rs['ms'])
    line += '; eff %.3f; ' % md['device_efficiency'] + ', '.join('busy %.1f kern %.1f fin %.1f' % (x['busy_ms'], x['kernel_ms'], x['finish_ms']) for x in md['devices'])
print(line)" $1 2>&1; }
same() { cmp -s $1 $2 && echo "  same bytes as $(basename $1)" || echo "  IMAGE DIFFERS from $(basename $1)"; }
r() { # tag, devices, scene variable, extra options
  local tag=$1 devs=$2 sc=$3; shift 3
  $B/rtcl ${!devs} ${!sc} -r 3 -q -o $T/$tag.ppm --stats $O/$tag.json "$@" 2>&1 | head -5
  echo "$tag: $(show $O/$tag.json)"; [ "$devs" = ONE ] || same $T/$sc-1-1.ppm $T/$tag.ppm; }
if [ -f $G/ompi/env.sh ]; then . $G/ompi/env.sh; fi
MPIRUN="mpirun --bind-to none"; [ $DRY = 1 ] && MPIRUN="$MPIRUN --oversubscribe"
m() { # tag, ranks, scene variable, extra options
  local tag=$1 n=$2 sc=$3; shift 3; local cmd="" i
  for ((i = 0; i < n; i++)); do cmd+="${cmd:+ : }-np 1 $B/rtcl-mpi --mpi -p $P -d $i ${!sc} -q -o $T/$tag.ppm --stats $O/$tag.json $*"; done
  local s=$(date +%s.%N); $MPIRUN $cmd 2>&1 | grep -v -e PMIx -e 'compression library' -e 'system. We will' -e 'large data streams' -e 'startup times' -e '^----' | head -5; local e=$(date +%s.%N)
  echo "$tag: $(show $O/$tag.json); mpirun $(python3 -c "print('%.0f ms' % (($e - $s) * 1e3))")"; same $T/$sc-1-1.ppm $T/$tag.ppm; }
fr() { # tag, devices, last frame
  mkdir -p $T/$1
  $B/rtcl ${!2} $F --frames 0:$3 -q -o $T/$1/f.ppm --stats $O/$1.json 2>&1 | head -3
  python3 -c "import json; d=json.load(open('$O/$1.json')); md=d.get('multidevice') or {}
print('$1: wall %.1f ms;' % d['wall_ms'], '; '.join('%d frames busy %.1f kern %.1f fin %.1f, %d renderer(s)' % (x['pieces'], x['busy_ms'], x['kernel_ms'], x['finish_ms'], x.get('renderers_opened', 0)) for x in md.get('devices', [])), '; eff %.3f' % md.get('device_efficiency', 1))" 2>&1; }
$B/rtcl $ONE $D --spp 4 -q -o $T/prime.ppm
for round in 1 2; do
  for sc in D L C W; do
    echo "== round $round, $sc: one process, 1, 2, 4 GPUs, -r 3"
    r $sc-1-$round ONE $sc; r $sc-2-$round TWO $sc; r $sc-4-$round FOUR $sc
    echo "== round $round, $sc: MPI, 1, 2, 4 ranks of one GPU, unbound, one render each"
    for n in 1 2 4; do m m$sc$n-$round $n $sc; done
  done
done
for sc in D L C W; do same $T/$sc-1-1.ppm $T/$sc-1-2.ppm; done
echo "== --frames: 0:15 and 0:5 on 1 GPU and on 4"
fr fr16-ONE ONE 15; fr fr16-FOUR FOUR 15; fr fr6-ONE ONE 5; fr fr6-FOUR FOUR 5
n16=0; n6=0
for k in $(seq -f %04g 0 15); do cmp -s $T/fr16-ONE/f_$k.ppm $T/fr16-FOUR/f_$k.ppm && n16=$((n16 + 1)); done
for k in $(seq -f %04g 0 5); do cmp -s $T/fr6-ONE/f_$k.ppm $T/fr6-FOUR/f_$k.ppm && n6=$((n6 + 1)); done
echo "frames the same bytes on 4 GPUs as on 1: $n16 of 16, $n6 of 6"
tar czf $OUT/batch99-json.tgz -C $T b99; date -u
rm -rf $T
