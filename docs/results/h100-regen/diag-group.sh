#!/bin/bash
# Issue 41: why -k persistent --fetch group gave an image other than
# dynamic's on an H100 for studio_path and materials_path (batch 105's
# run-fetch.sh; cornell the same bytes; every variant the same on PoCL).
# Variants of the group fetch on materials_path and cornell at 512x512,
# 16 spp, each compared with dynamic's image pixel by pixel: how many
# pixels differ, by how much, and whether they look untraced (zero) or
# traced twice (about double). About 40 s.
#   OUT=<folder> B=<binaries> bash docs/results/h100-regen/diag-group.sh
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b105}; OUT=${OUT:?}
[ -w /etc/OpenCL/vendors ] && [ -n "$(command -v nvidia-smi)" ] && echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
[ -x $B/rtcl-meshread ] && export RTCL_MESHREAD=$B/rtcl-meshread
P=${PLATFORM:-$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2; exit}')}
P=${P:-0}; T=$(mktemp -d); mkdir -p $OUT
SIZE=${SIZE:-512x512}; SPP=${SPP:-16}
cmpimg() { python3 -c "
import sys, numpy as np
def pfm(p):
    f = open(p, 'rb'); f.readline(); w, h = map(int, f.readline().split()); s = float(f.readline())
    return np.frombuffer(f.read(), '<f4' if s < 0 else '>f4').reshape(h, w, 3)
a, b = pfm(sys.argv[1]), pfm(sys.argv[2])
d = np.any(a != b, axis=2); n = int(d.sum())
if n == 0: print('  same pixels'); sys.exit()
ys, xs = np.nonzero(d); ra = a[d].sum(1); rb = b[d].sum(1)
ratio = rb / np.maximum(ra, 1e-9)
print('  %d pixels differ of %d; rows %d-%d cols %d-%d; zero in this %d; ratio this/dynamic median %.3f (min %.3f max %.3f); first (%d,%d)' % (n, d.size, ys.min(), ys.max(), xs.min(), xs.max(), int((rb == 0).sum()), np.median(ratio), ratio.min(), ratio.max(), xs[0], ys[0]))
" $1 $2; }
for sc in cornell materials_path studio_path; do
  $B/rtcl -p $P -d 0 scenes/$sc.json -k dynamic --size $SIZE --spp $SPP -q -o $T/ref.pfm
  while read -r tag args; do
    $B/rtcl -p $P -d 0 scenes/$sc.json $args --size $SIZE --spp $SPP -q -o $T/v.pfm --stats $OUT/$sc-$tag.json 2>&1 | head -3
    echo "$sc $tag ($args):"; cmpimg $T/ref.pfm $T/v.pfm
  done <<'LIST'
regen-group -k persistent --regenerate --fetch group
regen-group-q1 -k persistent --regenerate --fetch group --queues 1
group -k persistent --fetch group
group-b4 -k persistent --fetch group --batch 4
regen-group-w16 -k persistent --regenerate --fetch group -w 16x16
regen-group-again -k persistent --regenerate --fetch group
regen-item -k persistent --regenerate --fetch item
LIST
done
rm -rf $T
