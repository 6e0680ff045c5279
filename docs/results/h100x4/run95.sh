#!/bin/bash
# Issue 43, batch 95 (four H100s, nvidia-h100-x4): one image over 1, 2 and 4
# GPUs with the default split chosen by measurement (tiles_prefer_samples)
# and the sample split's sums in pinned memory, read back in parts that the
# host adds as they arrive; against a5dea23 (.gpu/rtcl-old: the fixed
# threshold of 128 samples per device, whole read-backs, 8 adding threads).
# 2000x2000, -k dynamic, -r 3 (median of 3 timed frames after a warm-up),
# two interleaved rounds of 1, 2, 4 GPUs on the default scene at 2048 spp and
# the lake (genbench.py lake, 2.1 M triangles) at 256 spp; every image
# compared byte for byte with one GPU's. Then the pixel split at 4 GPUs,
# a5dea23 at 4 GPUs, --frames over 1, 2, 4 GPUs, and MPI (Open MPI 4.1
# packed by tools/device/pack-openmpi.sh) over 1, 2, 4 ranks, unbound.
# Binaries carried in .gpu/ (rtcl: OIIO=0 MPI=0, rtcl-mpi: OIIO=0).
#   COMMIT=<commit> bash .gpu/run95.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d); O=$T/b95; mkdir -p $O
echo "commit: $COMMIT (old: a5dea23)"; nvidia-smi -L; nproc; date -u
$G/rtcl --list-devices
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ONE="-p $P -d 0"; TWO="--devices $P:0,$P:1"; FOUR="--devices $P:0,$P:1,$P:2,$P:3"
D="-k dynamic --size 2000x2000 --spp 2048"
python3 tools/genbench.py lake -o $T/lake > /dev/null
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
show() { python3 -c "
import json, statistics, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice')
f = d.get('frame_ms_all') or [d['kernel_ms']]
line = 'frame %.1f ms (wall per frame, median; all %s), kernel_ms %.1f' % (d['frame_ms'], ','.join('%.1f' % x for x in f), d['kernel_ms'])
if md:
    line += '; split %s' % md['split']
    c = md.get('split_choice')
    if c: line += ' (measured: render %.1f, pass %.1f/%d, sums %.2f vs penalty %.2f)' % (c['render_ms'], c['pass_ms'], c['pass_samples'], c['sums_ms'], c['penalty_ms'])
    line += '; eff %.3f; ' % md['device_efficiency'] + ', '.join('busy %.1f kern %.1f fin %.1f' % (x['busy_ms'], x['kernel_ms'], x['finish_ms']) for x in md['devices'])
print(line)" $1 2>&1; }
same() { cmp -s $1 $2 && echo "  same bytes as $(basename $1)" || echo "  IMAGE DIFFERS from $(basename $1)"; }
r() { # tag, binary, devices, scene variable, extra options
  local tag=$1 b=$2 devs=$3 sc=$4; shift 4
  $G/$b ${!devs} ${!sc} -r 3 -q -o $T/$tag.ppm --stats $O/$tag.json "$@" 2>&1 | head -5
  echo "$tag: $(show $O/$tag.json)"; }
# Programs into the cache (both binaries, both scenes), and a first check.
for b in rtcl rtcl-old; do for sc in D L; do $G/$b $ONE ${!sc} --spp 4 -q -o $T/prime.ppm; done; done
$G/rtcl $FOUR $D --size 256x256 --spp 64 -o $T/c4.ppm --stats $O/check4.json | tail -3
$G/rtcl $ONE $D --size 256x256 --spp 64 -q -o $T/c1.ppm; same $T/c1.ppm $T/c4.ppm
echo "== one image, 1, 2 and 4 GPUs, two interleaved rounds"
for round in 1 2; do
  for sc in D L; do
    r $sc-1-$round rtcl ONE $sc
    r $sc-2-$round rtcl TWO $sc; same $T/$sc-1-1.ppm $T/$sc-2-$round.ppm
    r $sc-4-$round rtcl FOUR $sc; same $T/$sc-1-1.ppm $T/$sc-4-$round.ppm
  done
done
echo "== 4 GPUs: the pixel split asked for; a5dea23's default and --split samples"
for sc in D L; do
  r $sc-4-dyn rtcl FOUR $sc --split dynamic; same $T/$sc-1-1.ppm $T/$sc-4-dyn.ppm
  r $sc-4-old rtcl-old FOUR $sc; same $T/$sc-1-1.ppm $T/$sc-4-old.ppm
  r $sc-4-oldsam rtcl-old FOUR $sc --split samples; same $T/$sc-1-1.ppm $T/$sc-4-oldsam.ppm
done
echo "== frames: 16 frames of the default scene at 256 spp (PPM), 1, 2, 4 GPUs; 6 frames on 4"
F="-k dynamic --size 2000x2000 --spp 256"
for n in ONE TWO FOUR; do
  mkdir -p $T/fr-$n
  $G/rtcl ${!n} $F --frames 0:15 -q -o $T/fr-$n/f.ppm --stats $O/fr-$n.json 2>&1 | head -3
  python3 -c "import json; d=json.load(open('$O/fr-$n.json')); md=d.get('multidevice') or {}
print('frames $n: wall %.1f ms' % d['wall_ms'], '; '.join('%d frames busy %.1f fin %.1f' % (x['pieces'], x['busy_ms'], x['finish_ms']) for x in md.get('devices', [])), 'eff %.3f' % md.get('device_efficiency', 1))" 2>&1
done
for k in 00 07 15; do same $T/fr-ONE/f_00$k.ppm $T/fr-FOUR/f_00$k.ppm; done
mkdir -p $T/fr6; $G/rtcl $FOUR $F --frames 0:5 -q -o $T/fr6/f.ppm --stats $O/fr6.json 2>&1 | head -3
python3 -c "import json; d=json.load(open('$O/fr6.json')); print('6 frames on 4: wall %.1f ms' % d['wall_ms'])"
echo "== MPI, unbound, one GPU a rank (image time, set-up before the clock; one run each)"
. $G/ompi/env.sh
m() { # tag, ranks, scene variable, extra options
  local tag=$1 n=$2 sc=$3; shift 3; local cmd="" i
  for ((i = 0; i < n; i++)); do cmd+="${cmd:+ : }-np 1 $G/rtcl-mpi --mpi -p $P -d $i ${!sc} -q -o $T/$tag.ppm --stats $O/$tag.json $*"; done
  mpirun --bind-to none $cmd 2>&1 | head -5
  echo "$tag: $(show $O/$tag.json)"; same $T/$sc-1-1.ppm $T/$tag.ppm; }
for round in 1 2; do m mD1-$round 1 D; m mD2-$round 2 D; m mD4-$round 4 D; done
m mL1 1 L; m mL4 4 L; m mL4-sam 4 L --split samples
tar czf $OUT/batch95-json.tgz -C $T b95; date -u
