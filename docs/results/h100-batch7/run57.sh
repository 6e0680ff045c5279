#!/bin/bash
# GPU batch 57 (issues 26 and 28): does the end of a launch cost what the
# chunks handed out last cost? An experiment switch (-DRTCL_X_REVERSE through
# RTCL_BUILD_OPTIONS) hands the chunks out bottom to top. The default scene's
# bottom (the table, its reflections) is its dear part, the lake's top (the
# far mountains); if a launch's idle end is the last chunks' cost, the
# default scene gets faster reversed and the lake slower. Three interleaved
# rounds; -r 20 at 1 spp, -r 3 at 1024 / 256 spp; the halves of batch 54.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; R=$G/rtcl-x
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
ms() { grep -o '"kernel_ms": [0-9.]*' $1 | head -1 | awk '{print $2}'; }
halves() { python3 -c "
import json, sys
md = json.load(open(sys.argv[1]))['multidevice']; k = [p['kernel_ms'] for p in md['pieces']]
print(' '.join('%.1f' % x for x in k), 'sum %.1f' % sum(k))" $1; }
for round in 1 2 3; do
  for v in plain reverse; do
    [ $v = reverse ] && export RTCL_BUILD_OPTIONS=-DRTCL_X_REVERSE || unset RTCL_BUILD_OPTIONS
    for k in dynamic persistent; do
      $R -p $P -k $k -w 8x8 --size 2000x2000 -r 20 -q -o $T/a-$v-$k.ppm --stats $T/s.json
      echo "round $round default 1spp $k $v $(ms $T/s.json)"
      $R -p $P -k $k -w 8x8 -s $T/lake/lake-10.json --size 2000x2000 -r 20 -q -o $T/l-$v-$k.ppm --stats $T/s.json
      echo "round $round lake 1spp $k $v $(ms $T/s.json)"
    done
    $R -p $P -k dynamic -w 8x8 --size 2000x2000 --spp 1024 -r 3 -q -o $T/b-$v.ppm --stats $T/s.json
    echo "round $round default 1024spp dynamic $v $(ms $T/s.json)"
    $R --devices $P:0 -k dynamic -w 8x8 --size 2000x2000 --spp 1024 -r 3 --piece-rows 1000 \
      --row-order interleave:2 -q -o $T/h-$v.ppm --stats $T/s.json
    echo "round $round default 1024spp halves $v $(halves $T/s.json)"
  done
done
unset RTCL_BUILD_OPTIONS
for f in a-%-dynamic a-%-persistent l-%-dynamic l-%-persistent b-% h-%; do
  a=$T/${f/\%/plain}.ppm; b=$T/${f/\%/reverse}.ppm
  cmp -s $a $b && echo "${f/-\%/}: images identical" || echo "${f/-\%/}: IMAGES DIFFER"
done
