#!/bin/bash
# Issue 41 (one H100): the wavefront's stages form (--wavefront-form stages,
# docs/wavefront.md "The stages form") against its bounce form and -k
# dynamic, on scenes/cornell.json and scenes/studio_path.json, 1024x1024, 64
# spp, -r 5 (median kernel time of 5 after a warm-up), two interleaved rounds:
# dynamic, wavefront bounce, wavefront stages with --paths-in-flight 256k, 1M
# (the default) and 4M, each sized from one counter read per iteration (the
# default) and with RTCL_STAGES_LAUNCH=device (launches that fill the GPU,
# counts read on the device, no wait). Every image is compared byte for byte with dynamic's;
# every --stats file is kept (wavefront_stages: per-kernel launches and
# times, path state moved, live paths per iteration), and a summary of the
# phases is printed for each stages run.
# Binaries: .gpu/wave41/ (rtcl, rtcl-meshread: make OIIO=0 MPI=0
# BUILD=build-gpu, branch wave41 at COMMIT); libraries in .gpu/lib.
#   COMMIT=<commit> bash docs/results/h100-stages/run.sh
# About 4-7 minutes: 32 renders of 6 frames each, and two program builds.
# Checked on PoCL at a tiny size:
#   LOCAL=1 BIN=$PWD SIZE=32x32 SPP=2 POOLS="64 256" OUT=/tmp/o bash docs/results/h100-stages/run.sh
set -u
LOCAL=${LOCAL:-0}
if [ "$LOCAL" = 1 ]; then
  B=${BIN:-$PWD}; MATCH=Portable
else
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
  export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
  B=${BIN:-$PWD/.gpu/wave41}; MATCH=NVIDIA
  export RTCL_MESHREAD=$B/rtcl-meshread
fi
SIZE=${SIZE:-1024x1024}; SPP=${SPP:-64}; POOLS=${POOLS:-262144 1048576 4194304}
T=$(mktemp -d); mkdir -p $OUT
exec > >(tee $OUT/run.txt) 2>&1
echo "commit: ${COMMIT:-?}"; nvidia-smi -L 2>/dev/null; date -u
P=$($B/rtcl --list-devices | awk -v m=$MATCH '/^Platform/ && $0 ~ m {sub("#","",$2); sub(":","",$2); print $2}')
echo "platform $P"
ms() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print('%.2f' % d['kernel_ms'])" $1; }
phases() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); st = d['wavefront_stages']; k = st['kernels']
total = sum(v['kernel_ms'] for v in k.values()) or 1
frames = k['begin']['launches']
print('  %d paths in flight, %d iterations, %.0f MB of path state a frame' % (st['paths_in_flight'], st['iterations'], st['state_bytes'] / frames / 1e6))
print('  per frame: ' + ', '.join('%s %.1f ms (%d%%, %d launches)' % (n, v['kernel_ms'] / frames, 100 * v['kernel_ms'] / total, v['launches'] // frames) for n, v in k.items() if v['launches']))
live = st['live_paths']
print('  live paths per iteration (every 8th): ' + ' '.join(str(x) for x in live[::8]))
" $1; }
for sc in cornell studio_path; do
  # build (and cache) both programs outside the timed runs
  $B/rtcl -p $P -d 0 -k dynamic scenes/$sc.json --size 64x64 --spp $SPP -q -o $T/prime.pfm
  $B/rtcl -p $P -d 0 -k wavefront scenes/$sc.json --size 64x64 --spp $SPP -q -o $T/prime.pfm
  for round in 1 2; do
    runs="dynamic bounce"; for n in $POOLS; do runs="$runs stages-$n device-$n"; done
    for run in $runs; do
      case $run in
        dynamic) args="-k dynamic" ;;
        bounce) args="-k wavefront" ;;
        stages-*) args="-k wavefront --wavefront-form stages --paths-in-flight ${run#stages-}" ;;
        device-*) args="-k wavefront --wavefront-form stages --paths-in-flight ${run#device-}" ;;
      esac
      launch=sync; case $run in device-*) launch=device ;; esac
      s=$OUT/$sc-$run-$round.json
      RTCL_STAGES_LAUNCH=$launch $B/rtcl -p $P -d 0 $args scenes/$sc.json --size $SIZE --spp $SPP -r 5 -q \
        -o $T/$sc-$run.pfm --stats $s > $T/log 2>&1 || { echo "$sc $run FAILED"; cat $T/log; continue; }
      t=$(ms $s)
      echo "$sc $run round $round: $t ms, $(python3 -c "print('%.1f' % ($(echo $SIZE | tr x '*')*$SPP/$t/1e3))") M paths/s"
      case $run in stages-*|device-*) phases $s ;; esac
    done
  done
  for run in $runs; do
    [ $run = dynamic ] && continue
    cmp -s $T/$sc-dynamic.pfm $T/$sc-$run.pfm && echo "$sc $run: same bytes as dynamic" || echo "$sc $run: IMAGE DIFFERS from dynamic"
  done
done
date -u
rm -rf $T
