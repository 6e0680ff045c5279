#!/bin/bash
# GPU batch 23 (issue 22 item 3): what the progress line costs. Every
# single-pass kernel and the wavefront on the default scene (2000x2000), at 1
# spp (-r 20: one launch a frame) and 16 spp (-r 5: four passes a frame, the
# line polled during each), three interleaved rounds of
#   old:  rtcl-561d019, before the progress line
#   off:  rtcl ($COMMIT), stderr a file: no line, no -DRTCL_PROGRESS, no polling
#   on:   rtcl ($COMMIT), stderr a terminal (.gpu/pty_run.py): the line, with
#         -DRTCL_PROGRESS (one atomic a chunk in serial/naive/cyclic) and the
#         work counter read every 100 ms on a second queue
# Median kernel_ms of each run; images compared (old/off/on); then a long
# render on a terminal, to see the share move during one launch on the GPU.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 561d019 (rtcl-561d019)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "NVIDIA platform: $P"
ms() { python3 -c 'import json,sys; print("%.4f" % json.load(open(sys.argv[1]))["kernel_ms"])' "$1"; }
run() { # variant kernel spp repeat
  local v=$1 k=$2 spp=$3 r=$4 bin=$G/rtcl
  [ "$v" = old ] && bin=$G/rtcl-561d019
  local args=(-p "$P" -k "$k" --spp "$spp" -r "$r" -o "$T/$v-$k-$spp.ppm" --stats "$T/$v-$k-$spp.json")
  if [ "$v" = on ]; then python3 $G/pty_run.py "$T/pty-$k-$spp.txt" "$bin" "${args[@]}" > /dev/null
  else "$bin" "${args[@]}" > /dev/null 2> "$T/err.txt"; fi || { echo "FAILED $v $k $spp"; cat "$T/err.txt"; return; }
  printf "  round %s %-4s %-10s spp %-3s %s ms\n" "$round" "$v" "$k" "$spp" "$(ms "$T/$v-$k-$spp.json")"
}
for round in 1 2 3; do
  for k in naive cyclic dynamic persistent wavefront; do
    for spp in 1 16; do
      r=20; [ "$spp" = 16 ] && r=5
      for v in old off on; do run $v $k $spp $r; done
    done
  done
done
echo "== images (pixels) old/off/on"
for k in naive cyclic dynamic persistent wavefront; do for spp in 1 16; do
  a=$(tail -c +20 $T/old-$k-$spp.ppm | md5sum | cut -c1-12); b=$(tail -c +20 $T/off-$k-$spp.ppm | md5sum | cut -c1-12); c=$(tail -c +20 $T/on-$k-$spp.ppm | md5sum | cut -c1-12)
  echo "  $k spp $spp: $a $b $c $([ "$a" = "$b" ] && [ "$b" = "$c" ] && echo identical || echo DIFFER)"
done; done
echo "== build options with the line on (pty) and off"
grep -o '"build_options": "[^"]*"' $T/on-naive-1.json $T/off-naive-1.json
echo "== a long render on a terminal: the shares shown during one launch"
for k in naive cyclic dynamic persistent wavefront; do
  python3 $G/pty_run.py $T/long-$k.txt $G/rtcl -p $P -k $k --spp 2048 -o $T/long.ppm > /dev/null
  printf "  %-10s %s\n" $k "$(tr '\r' '\n' < $T/long-$k.txt | grep -o '[0-9]*% done' | uniq | tr '\n' ' ' | cut -c1-300)"
done
tr '\r' '\n' < $T/long-dynamic.txt | grep -v '^$' | head -5
