#!/bin/bash
# Issue 41, a short check on one H100 of the stages form after branch
# wave41b (docs/wavefront.md, "Cost per iteration": the logic kernel over the
# paths that ended only, the extension kernel sorting the paths by the BSDF
# kind hit). scenes/cornell.json and scenes/materials_path.json at SIZE
# 1024x1024, SPP 64, -r REPEAT (3: the median kernel time of 3 after a
# warm-up): -k dynamic (the reference image), -k wavefront (the bounce form)
# and --wavefront-form stages with --paths-in-flight 1M and 4M (POOLS).
# Printed per run: the kernel time, and per stage kernel its time, launches
# and work-items per frame (--stats' wavefront_stages, summed over the
# warm-up and the REPEAT frames, divided by them); every image compared byte
# for byte with dynamic's. With BASE (a folder holding the rtcl of the
# commit before, e.g. .gpu/study41) the stages runs are made with it too,
# for a before/after on the same card.
#
# From the repository root on the device:
#   COMMIT=<commit> OUT=<folder> bash docs/results/h100-stages/run101.sh
# Binaries: $B (default .gpu/wave41b): rtcl (and rtcl-meshread) of COMMIT,
# built with make OIIO=0 MPI=0 BUILD=build-gpu; libraries in .gpu/lib.
# About 60 s on one H100 (two program builds a scene, 8 renders of 4 frames;
# 12 with BASE). On PoCL (a check of the script, not a measurement):
#   OUT=/tmp/o B=. PLATFORM=0 SIZE=32x32 SPP=2 POOLS="64 256" REPEAT=1 \
#     bash docs/results/h100-stages/run101.sh
# Everything lands under $OUT: log.txt and the --stats files.
set -u
ROOT=$PWD
B=${B:-$ROOT/.gpu/wave41b}; BASE=${BASE:-}
SIZE=${SIZE:-1024x1024}; SPP=${SPP:-64}; REPEAT=${REPEAT:-3}; POOLS=${POOLS:-1048576 4194304}
OUT=${OUT:?OUT must name the folder for the results}
[ -e /etc/OpenCL/vendors ] && [ -w /etc/OpenCL/vendors ] && [ -n "$(command -v nvidia-smi)" ] &&
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
[ -x $B/rtcl-meshread ] && export RTCL_MESHREAD=$B/rtcl-meshread
RTCL=$B/rtcl
T=$(mktemp -d); mkdir -p $OUT
exec > >(tee $OUT/log.txt) 2>&1
echo "commit: ${COMMIT:-unknown}; rtcl: $RTCL; base: ${BASE:-none}"; nvidia-smi -L 2>/dev/null; date -u
P=${PLATFORM:-$($RTCL --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2; exit}')}
P=${P:-0}; DEV="-p $P -d 0"
echo "platform $P: $($RTCL --list-devices | grep -A1 "^Platform #$P" | tail -1)"

# The kernel time of a --stats file, and for the stages form each stage
# kernel's time, launches and work-items per frame.
report() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); frames = d['repeat'] + 1
print('  kernel_ms %.2f (rounds %.2f-%.2f)' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max']))
st = d.get('wavefront_stages')
if st:
    print('  %d paths in flight, %d iterations a frame, %.0f MB of path state a frame' % (
        st['paths_in_flight'], st['iterations'], st['state_bytes'] / frames / 1e6))
    for n, v in st['kernels'].items():
        if v['launches']:
            print('    %-17s %8.2f ms %6d launches %8.3f M items a frame' % (
                n, v['kernel_ms'] / frames, v['launches'] // frames, v['items'] / frames / 1e6))
" $1; }

for sc in cornell materials_path; do
  f=scenes/$sc.json
  runs="dynamic bounce"
  for n in $POOLS; do runs="$runs stages-$n"; [ -n "$BASE" ] && runs="$runs base-$n"; done
  for run in $runs; do
    rtcl=$RTCL
    case $run in
      dynamic) args="-k dynamic" ;;
      bounce) args="-k wavefront --wavefront-form bounce" ;;
      stages-*) args="-k wavefront --wavefront-form stages --paths-in-flight ${run#stages-}" ;;
      base-*) rtcl=$BASE/rtcl
              args="-k wavefront --wavefront-form stages --paths-in-flight ${run#base-}" ;;
    esac
    s=$OUT/${sc}__$run.json
    echo "== $sc $run: $args"
    if ! $rtcl $DEV $f $args --size $SIZE --spp $SPP -r $REPEAT -q -o $T/$run.pfm --stats $s; then
      echo "  FAILED"; continue
    fi
    report $s
    if [ $run != dynamic ]; then
      cmp -s $T/$run.pfm $T/dynamic.pfm && echo "  image: same bytes as dynamic's" ||
        echo "  image: DIFFERS from dynamic's"
    fi
  done
done
date -u
