#!/bin/bash
# Issue 43, batch 106 (branch frames43 at COMMIT): --frames 0:15 and 0:5 of
# the default scene's orbit (2000x2000, 256 spp, -k dynamic) on 1 and 4 GPUs
# of one host (nvidia-h100-x4), each of RTCL_FRAMES_READ's three ways, two
# interleaved rounds. Every frame is compared with cmp against one GPU's
# (round 1, inline: the way of batch 100).
# What it checks: batch 100's devices of four were busy 155-182 ms beyond
# their kernels over their 4 frames (one GPU about 60 over 16), all in their
# first frames, where each device's thread pinned two 48 MB images (pinning
# seems to take the process about 2 GB/s however many devices pin at once).
# "aside" (the new default) copies each frame on its device and reads it
# back in the frame's stager thread into one pinned image a device (pinned
# there); "pageable" reads it there into memory of malloc, nothing pinned;
# "inline" is batch 100's way. Each line gives a device's first frame
# (first_piece_ms), its renderer's opening in it (open_ms) and its last.
# Expected with aside or pageable: every frame about its kernels, the first
# its kernels + the opening, 16 frames on 4 GPUs about 690 ms (the kernels
# of the costliest device, 637 ms in batch 100, + the last frame's staging,
# ~45 ms) against 836, one GPU about 2330 against 2388. About 100 s of commands.
#
# Binary (built on the VM, carried in .gpu/frames43/, or the folder B names):
#   make OIIO=0 MPI=0 BUILD=build-gpu BIN=.gpu/frames43/rtcl
# with .gpu/lib (libjansson, ocl-icd) beside it. On the device, from the
# repository root, carrying .gpu/frames43 and .gpu/lib:
#   COMMIT=<commit> bash docs/results/h100x4/run106-frames.sh
# Without an NVIDIA platform (a dry run on PoCL: OUT=/tmp/x bash run106-frames.sh) it
# renders tiny frames on four PoCL CPU devices taken as GPUs instead.
set -u
G=$PWD/.gpu; B=${B:-$G/frames43}; T=$(mktemp -d); O=$T/b106; mkdir -p $O
OUT=${OUT:-$(mktemp -d)}; mkdir -p $OUT
if command -v nvidia-smi > /dev/null; then
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
  export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$G/lib:${LD_LIBRARY_PATH:-}
fi
exec > >(tee $OUT/run106-frames.txt) 2>&1
echo "commit: ${COMMIT:-unknown}"; nvidia-smi -L 2> /dev/null; nproc; date -u
P=$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
if [ -n "$P" ]; then
  F="-k dynamic --size 2000x2000 --spp 256"
else
  # Dry run: four PoCL CPU devices, taken as GPUs (the GPUs' choices), tiny.
  echo "no NVIDIA platform: a dry run on PoCL"
  P=0
  export POCL_DEVICES="pthread pthread pthread pthread" RTCL_TEST_AS_GPUS=1
  F="-k dynamic --size 48x32 --spp 4"
fi
ONE="-p $P -d 0"; FOUR="--devices $P:0,$P:1,$P:2,$P:3"
fr() { # tag, devices, last frame, way
  mkdir -p $T/$1
  RTCL_FRAMES_READ=$4 $B/rtcl ${!2} $F --frames 0:$3 -q -o $T/$1/f.ppm --stats $O/$1.json 2>&1 | head -3
  python3 -c "import json; d=json.load(open('$O/$1.json')); md=d.get('multidevice') or {}
print('$1: wall %.1f ms, read %s;' % (d['wall_ms'], md.get('frames_read')), '; '.join('%d frames busy %.1f kern %.1f (beyond %.1f) first %.1f (open %.1f) last %.1f fin %.1f setup %.1f, %d renderer(s)' % (x['pieces'], x['busy_ms'], x['kernel_ms'], x['busy_ms'] - x['kernel_ms'], x.get('first_piece_ms', -1), x.get('open_ms', -1), x['last_piece_ms'], x['finish_ms'], x['setup_ms'], x.get('renderers_opened', 0)) for x in md.get('devices', [])), '; eff %.3f' % md.get('device_efficiency', 1))" 2>&1
  local n=$(($3 + 1)) same=0 k
  for k in $(seq -f %04g 0 $3); do cmp -s $T/fr$n-ONE-inline-1/f_$k.ppm $T/$1/f_$k.ppm && same=$((same + 1)); done
  echo "  $same of $n frames the same bytes as fr$n-ONE-inline-1's"; }
$B/rtcl $ONE $F --spp 4 -q -o $T/prime.ppm
for round in 1 2; do
  for way in inline aside pageable; do
    echo "== round $round, RTCL_FRAMES_READ=$way: 0:15 and 0:5 on 1 GPU and on 4"
    fr fr16-ONE-$way-$round ONE 15 $way; fr fr16-FOUR-$way-$round FOUR 15 $way
    fr fr6-ONE-$way-$round ONE 5 $way; fr fr6-FOUR-$way-$round FOUR 5 $way
  done
done
tar czf $OUT/batch106-frames-json.tgz -C $T b106; date -u
rm -rf $T
