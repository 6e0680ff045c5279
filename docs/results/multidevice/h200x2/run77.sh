#!/bin/bash
# Issue 28, batch 77 (one H200): one GPU with each sample's fixed-point colour
# added in place in the sums buffer by 64-bit atomics (RTCL_BUILD_OPTIONS=
# -DRTCL_SUM_ATOMIC: no load, no sum in registers across a trace), against
# the sum in registers (the default) and 98ef897's float sums
# (.gpu/rtcl-base). Default scene 2000x2000 at 2048 spp, the lake at 256
# spp, kernel dynamic, -r 3, two interleaved rounds.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run77.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; B=$G/rtcl-base
T=$(mktemp -d); O=$T/json77; mkdir -p $O
echo "commit: $COMMIT (base: 98ef897)"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
print('kernels %.1f ms (min %.1f, max %.1f), wall %.1f' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan'))))" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
for s in D L; do
  $B -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm
  RTCL_BUILD_OPTIONS=-DRTCL_SUM_ATOMIC $R -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm
  $R -p $P -d 0 ${!s} -q -o $T/$s.ppm
done
for round in 1 2; do
  for s in D L; do
    $B -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-base-$round.json
    echo "$s one GPU, float sums (98ef897), round $round: $(show $O/$s-base-$round.json)"
    $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-reg-$round.json
    echo "$s one GPU, sum in registers, round $round: $(show $O/$s-reg-$round.json)"; same $T/$s.ppm $T/x.ppm
    RTCL_BUILD_OPTIONS=-DRTCL_SUM_ATOMIC $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-mem-$round.json
    echo "$s one GPU, sum added in place by atomics, round $round: $(show $O/$s-mem-$round.json)"; same $T/$s.ppm $T/x.ppm
  done
done
tar czf $OUT/batch77-json.tgz -C $T json77
