#!/bin/bash
# Issue 43, batch 96 (four H100s, nvidia-h100-x4): batch 95's one-image
# table again after c6cf709 (see README.md): the sample split's add of
# the devices' sums after the frames' clock again (as at a5dea23, and as one
# GPU reads its image back after it), its choice counting that add, and the
# shares of the samples from each device's rate over all frames so far.
# 2000x2000, -k dynamic, -r 3, two interleaved rounds of 1, 2, 4 GPUs, the
# default scene at 2048 spp and the lake at 256 spp, every image compared
# byte for byte with one GPU's; then one single render (no -r) of each on 4
# GPUs and on 1 for the whole time with the image's assembly.
#   COMMIT=<commit> bash .gpu/run96.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d); O=$T/b96; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L; nproc; date -u
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ONE="-p $P -d 0"; TWO="--devices $P:0,$P:1"; FOUR="--devices $P:0,$P:1,$P:2,$P:3"
D="-k dynamic --size 2000x2000 --spp 2048"
python3 tools/genbench.py lake -o $T/lake > /dev/null
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice'); t = d['time_breakdown_ms']
f = d.get('frame_ms_all') or [d['kernel_ms']]
line = 'frame %.1f ms (median; all %s), read_back %.1f' % (d.get('frame_ms', d['kernel_ms']), ','.join('%.1f' % x for x in f), t['read_back'])
if md:
    line += '; split %s' % md['split']
    c = md.get('split_choice')
    if c: line += ' (measured: render %.1f, pass %.1f/%d, sums %.2f + add %.2f vs penalty %.2f)' % (c['render_ms'], c['pass_ms'], c['pass_samples'], c['sums_ms'], c['add_ms'], c['penalty_ms'])
    line += '; eff %.3f; ' % md['device_efficiency'] + ', '.join('%s busy %.1f kern %.1f' % (p['samples'], x['busy_ms'], x['kernel_ms']) for x, p in zip(md['devices'], sorted(md['pieces'], key=lambda p: p['device'])))
print(line)" $1 2>&1; }
same() { cmp -s $1 $2 && echo "  same bytes as $(basename $1)" || echo "  IMAGE DIFFERS from $(basename $1)"; }
r() { # tag, devices, scene variable, extra options
  local tag=$1 devs=$2 sc=$3; shift 3
  $G/rtcl ${!devs} ${!sc} -q -o $T/$tag.ppm --stats $O/$tag.json "$@" 2>&1 | head -5
  echo "$tag: $(show $O/$tag.json)"; }
for sc in D L; do $G/rtcl $ONE ${!sc} --spp 4 -q -o $T/prime.ppm; done
echo "== one image, 1, 2 and 4 GPUs, -r 3, two interleaved rounds"
for round in 1 2; do
  for sc in D L; do
    r $sc-1-$round ONE $sc -r 3
    r $sc-2-$round TWO $sc -r 3; same $T/$sc-1-1.ppm $T/$sc-2-$round.ppm
    r $sc-4-$round FOUR $sc -r 3; same $T/$sc-1-1.ppm $T/$sc-4-$round.ppm
  done
done
echo "== one render each (no -r): whole process"
for sc in D L; do
  for n in ONE FOUR; do
    s=$(date +%s.%N); r $sc-$n-single $n $sc; e=$(date +%s.%N)
    echo "  process $(python3 -c "print('%.0f ms' % (($e - $s) * 1e3))")"; same $T/$sc-1-1.ppm $T/$sc-$n-single.ppm
  done
done
tar czf $OUT/batch96-json.tgz -C $T b96; date -u
