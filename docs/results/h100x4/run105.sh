#!/bin/bash
# Issue 43, batch 105: --frames over four GPUs (the default scene's orbit,
# 2000x2000, 256 spp, -k dynamic, PPM frames): 0:15 and 0:5 on one GPU and
# on four, two interleaved rounds; every frame compared with cmp against
# one GPU's. The lines give the wall time and, per device, its frames, busy,
# kernel and finish times, its last piece's busy time and its set-up time
# (--stats multidevice.devices). Batch 104 (b3bc6ef, four H200s): 0:15
# 2405.6 ms on one GPU, 884.9 on four (2.72x); 0:5 971.3 and 798.3 (1.22x).
# About 30 s of commands.
#   COMMIT=<commit> OUT=<folder> B=<binaries> bash docs/results/h100x4/run105.sh
# Without an NVIDIA platform (a dry run on PoCL) it renders tiny frames on
# four PoCL CPU devices taken as GPUs instead.
set -u
G=$PWD/.gpu; B=${B:-$G/b105}; T=$(mktemp -d); O=$T/b105; mkdir -p $O
OUT=${OUT:-$(mktemp -d)}; mkdir -p $OUT
if command -v nvidia-smi > /dev/null; then
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
  export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$G/lib:${LD_LIBRARY_PATH:-}
fi
exec > >(tee $OUT/run105.txt) 2>&1
echo "commit: ${COMMIT:-unknown}"; nvidia-smi -L 2> /dev/null; nproc; date -u
P=$($B/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
if [ -n "$P" ]; then
  F="-k dynamic --size 2000x2000 --spp 256"
else
  echo "no NVIDIA platform: a dry run on PoCL"; P=0
  export POCL_DEVICES="pthread pthread pthread pthread" RTCL_TEST_AS_GPUS=1
  F="-k dynamic --size 48x32 --spp 4"
fi
ONE="-p $P -d 0"; FOUR="--devices $P:0,$P:1,$P:2,$P:3"
fr() { # tag, devices, last frame
  mkdir -p $T/$1
  $B/rtcl ${!2} $F --frames 0:$3 -q -o $T/$1/f.ppm --stats $O/$1.json 2>&1 | head -3
  python3 -c "import json; d=json.load(open('$O/$1.json')); md=d.get('multidevice') or {}
print('$1: wall %.1f ms;' % d['wall_ms'], '; '.join('%d frames busy %.1f kern %.1f last %.1f fin %.1f setup %.1f' % (x['pieces'], x['busy_ms'], x['kernel_ms'], x.get('last_piece_ms', 0), x['finish_ms'], x.get('setup_ms', 0)) for x in md.get('devices', [])), '; eff %.3f' % md.get('device_efficiency', 1))" 2>&1; }
$B/rtcl $ONE $F --spp 4 -q -o $T/prime.ppm
for round in 1 2; do
  echo "== round $round"
  fr fr16-ONE-$round ONE 15; fr fr16-FOUR-$round FOUR 15; fr fr6-ONE-$round ONE 5; fr fr6-FOUR-$round FOUR 5
done
n16=0; n6=0
for r in 1 2; do
  for k in $(seq -f %04g 0 15); do cmp -s $T/fr16-ONE-1/f_$k.ppm $T/fr16-FOUR-$r/f_$k.ppm && n16=$((n16 + 1)); done
  for k in $(seq -f %04g 0 5); do cmp -s $T/fr6-ONE-1/f_$k.ppm $T/fr6-FOUR-$r/f_$k.ppm && n6=$((n6 + 1)); done
done
echo "frames the same bytes on 4 GPUs as on 1: $n16 of 32, $n6 of 12"
python3 -c "
import json
for n in (16, 6):
    for r in (1, 2):
        one = json.load(open('$O/fr%d-ONE-%d.json' % (n, r)))['wall_ms']; four = json.load(open('$O/fr%d-FOUR-%d.json' % (n, r)))['wall_ms']
        print('%d frames, round %d: one GPU %.1f ms, four %.1f ms: %.2fx' % (n, r, one, four, one / four))"
tar czf $OUT/batch105-json.tgz -C $T b105; date -u
rm -rf $T
