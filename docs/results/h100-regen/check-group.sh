#!/bin/bash
# Issue 41: --regenerate --fetch group after its blocks moved to global
# memory, on the card that showed the defect (one H100, batch 105: 2-21
# pixels of 262,144 lost or repeated on materials_path and studio_path).
# Three renders of each scene at 512x512, 16 spp, each compared pixel by
# pixel with dynamic's (diag-group.sh's comparison). About 40 s.
#   OUT=<folder> B=<binaries> bash docs/results/h100-regen/check-group.sh
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b107}; OUT=${OUT:?}
[ -w /etc/OpenCL/vendors ] && [ -n "$(command -v nvidia-smi)" ] && echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
[ -x $B/rtcl-meshread ] && export RTCL_MESHREAD=$B/rtcl-meshread
P=${PLATFORM:-$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2; exit}')}
P=${P:-0}; T=$(mktemp -d); mkdir -p $OUT
nvidia-smi -L 2> /dev/null
for sc in materials_path studio_path cornell; do
  $B/rtcl -p $P -d 0 scenes/$sc.json -k dynamic --size 512x512 --spp 16 -q -o $T/ref.pfm
  for i in 1 2 3; do
    $B/rtcl -p $P -d 0 scenes/$sc.json -k persistent --regenerate --fetch group --size 512x512 --spp 16 -q -o $T/v.pfm
    cmp -s $T/ref.pfm $T/v.pfm && echo "$sc regen-group $i: same bytes as dynamic" || echo "$sc regen-group $i: IMAGE DIFFERS"
  done
done | tee $OUT/check-group.txt
rm -rf $T
