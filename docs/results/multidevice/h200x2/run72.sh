#!/bin/bash
# Issue 28, batch 72 (two H200s), 9e20ce2: what the fixed-point sums cost one
# GPU. The float sums of 98ef897 (.gpu/rtcl-base) against the fixed point
# with the channels converted by integer shifts (the default), by OpenCL's
# convert_long_rte (RTCL_BUILD_OPTIONS=-DRTCL_FIX_CONVERT), and in GPU
# passes of 8 samples instead of 4 (.gpu/rtcl-x: run72-experiment.patch,
# RTCL_X_PASS_SAMPLES=8); two GPUs split by samples, passes of 4 and 8.
# Default scene 2000x2000 at 2048 spp, the lake at 256 spp, kernel dynamic,
# -r 3, two interleaved rounds.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run72.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl; B=$G/rtcl-base; X=$G/rtcl-x
T=$(mktemp -d); O=$T/json72; mkdir -p $O
echo "commit: $COMMIT (base: 98ef897)"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); md = d.get('multidevice'); t = d.get('time_breakdown_ms', {})
line = 'kernels %.1f ms (min %.1f, max %.1f), wall %.1f, %d queues, %d passes, assemble %.1f ms' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), d.get('queues', 0), d.get('passes', 0), t.get('read_back', float('nan')))
if md:
    line += '; split %s; ' % md['split'] + ', '.join('dev %d: %d px, busy %.1f, kernels %.1f' % (k,
        x['pixels'], x['busy_ms'], x['kernel_ms']) for k, x in enumerate(md['devices']))
print(line)" $1; }
same() { cmp -s $1 $2 && echo "  image identical" || echo "  IMAGE DIFFERS from $1"; }
D="-k dynamic --size 2000x2000 --spp 2048"
L="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256"
for s in D L; do
  for Y in $R $B; do $Y -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm; done  # program caches
  RTCL_BUILD_OPTIONS=-DRTCL_FIX_CONVERT $R -p $P -d 0 ${!s} --size 64x64 -q -o $T/prime.ppm
  $R -p $P -d 0 ${!s} -q -o $T/$s.ppm
done
for round in 1 2; do
  for s in D L; do
    $B -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-base-$round.json
    echo "$s one GPU, float sums (98ef897), round $round: $(show $O/$s-base-$round.json)"
    $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-bits-$round.json
    echo "$s one GPU, integer shifts, round $round: $(show $O/$s-bits-$round.json)"; same $T/$s.ppm $T/x.ppm
    RTCL_BUILD_OPTIONS=-DRTCL_FIX_CONVERT $R -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-convert-$round.json
    echo "$s one GPU, convert_long_rte, round $round: $(show $O/$s-convert-$round.json)"; same $T/$s.ppm $T/x.ppm
    RTCL_X_PASS_SAMPLES=8 $X -p $P -d 0 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-pass8-$round.json
    echo "$s one GPU, passes of 8, round $round: $(show $O/$s-pass8-$round.json)"; same $T/$s.ppm $T/x.ppm
    $R --devices $P:0,$P:1 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-two-$round.json
    echo "$s two GPUs (samples), round $round: $(show $O/$s-two-$round.json)"; same $T/$s.ppm $T/x.ppm
    RTCL_X_PASS_SAMPLES=8 $X --devices $P:0,$P:1 ${!s} -r 3 -q -o $T/x.ppm --stats $O/$s-two8-$round.json
    echo "$s two GPUs (samples), passes of 8, round $round: $(show $O/$s-two8-$round.json)"; same $T/$s.ppm $T/x.ppm
  done
done
tar czf $OUT/batch72-json.tgz -C $T json72
