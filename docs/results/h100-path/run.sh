#!/bin/bash
# Issue 40, batch 98 (one H100): the path tracer's speed against Mitsuba 3 on the
# same GPU, same call. 1024x1024, 64 spp, rtcl max_depth 6 = Mitsuba max_depth 8
# (docs/oracle.md: rtcl counts bounces after the first hit). Scenes:
# scenes/cornell.json (Mitsuba's cornell_box exported) and cornell_blob.json (its
# room and a 1.3 M-triangle displaced sphere of rough gold, GGX alpha 0.15).
# rtcl: naive, dynamic, persistent, wavefront (serial: one work-item, and
# cyclic: not timed in this batch), -r 3 (median kernel time of 3 after a warm-up), two interleaved
# rounds, images compared byte for byte across kernels. Mitsuba 3.9.1
# cuda_ad_rgb (OptiX): the same scenes through tools/build/mitsuba_ref.py's
# mapping, and mi.cornell_box() at max_depth 8, megakernel and wavefront,
# median of 3 after a compiling render.
#   COMMIT=<commit> bash .gpu-pt/run.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
G=$PWD/.gpu-pt; T=/tmp/pt; mkdir -p $T; tar xJf $G/bin.tar.xz -C $T
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$T/lib:${LD_LIBRARY_PATH:-} RTCL_MESHREAD=$T/rtcl-meshread
echo "commit: $COMMIT"; nvidia-smi -L; date -u
python3 $G/blob.py scenes/models/blob.ply 8; cp $G/cornell_blob.json scenes/
P=$($T/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "platform $P"
ms() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print('%.2f' % d['kernel_ms'])" $1; }
for sc in cornell cornell_blob; do
  $T/rtcl -p $P -d 0 scenes/$sc.json --size 1024x1024 --spp 64 -o $T/prime.ppm 2>&1 | tail -3
  for round in 1 2; do
    for k in naive dynamic persistent wavefront; do
      $T/rtcl -p $P -d 0 -k $k scenes/$sc.json --size 1024x1024 --spp 64 -r 3 -q \
        -o $T/$sc-$k.pfm --stats $OUT/$sc-$k-$round.json > $T/log 2>&1 || { echo "$sc $k FAILED"; cat $T/log; continue; }
      t=$(ms $OUT/$sc-$k-$round.json)
      echo "rtcl $sc $k round $round: $t ms, $(python3 -c "print('%.1f' % (1024*1024*64/$t/1e3))") M paths/s"
    done
  done
  for k in naive persistent wavefront; do cmp -s $T/$sc-dynamic.pfm $T/$sc-$k.pfm && echo "$sc $k: same bytes as dynamic" || echo "$sc $k: IMAGE DIFFERS from dynamic"; done
done
$T/rtcl -p $P -d 0 -k dynamic scenes/cornell.json --size 1024x1024 --spp 64 -v -o $T/v.ppm 2>&1 | grep -iE "register|spill|build|time|rays" | head -12
mkdir -p /tmp/site; tar xJf $G/mi/mitsuba-cp312.tar.xz -C /tmp/site
PYTHONPATH=/tmp/site timeout 200 python3 $G/pt_mitsuba.py cuda_ad_rgb 1024 64 2>&1 | grep -v Warning
date -u
# Issue 42's incoherent-ray batch (branch incoherent, docs/results/h100-incoherent/run.sh), its libraries from bin.tar.xz
[ "${SKIP_RAYS:-0}" = 1 ] || bash .gpu/incoherent/run.sh 2>&1 | tail -60
date -u
# Everything under $OUT as one archive (at most 8 files come back)
(cd $OUT && tar czf /tmp/batch98.tgz . && rm -rf ./* && mv /tmp/batch98.tgz .)
