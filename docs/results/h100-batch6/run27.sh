#!/bin/bash
# GPU batch 27: the session's merged main ($COMMIT: issue 22's progress line,
# issue 24's fixes, camera-relative rendering among them) against 561d019, the
# session's start. Every kernel on paper60 (the default scene), two_balls and
# glass_mesh (meshes), -r 10, two interleaved rounds: kernel times, and whether
# every kernel's image is byte-identical to the others (new) and to the old
# binary's. Pixels only: headers name the kernel.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 561d019 (rtcl-561d019)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
ms() { python3 -c 'import json,sys; print("%.4f" % json.load(open(sys.argv[1]))["kernel_ms"])' "$1"; }
pix() { python3 -c 'import hashlib,sys; sys.path.insert(0,"tools"); from rtcl_tools import ppm; print(hashlib.md5(ppm.pixels(sys.argv[1])[1]).hexdigest()[:12])' "$1"; }
for round in 1 2; do
  for s in paper60 two_balls glass_mesh; do
    scene=(); [ $s != paper60 ] && scene=(-s scenes/$s.json)
    for k in naive cyclic dynamic persistent wavefront; do
      for b in rtcl-561d019 rtcl; do
        $G/$b -p $P -k $k -r 10 "${scene[@]}" -o $T/$b-$s-$k.ppm --encoding linear -q --stats $T/st.json 2> $T/err.txt || { echo "FAILED $b $s $k: $(head -2 $T/err.txt)"; continue; }
        printf "  round %s %-13s %-10s %-10s %s ms\n" $round $b $s $k "$(ms $T/st.json)"
      done
    done
  done
done
echo "== pixels (md5 of the pixel bytes): old | new; new kernels against new dynamic"
for s in paper60 two_balls glass_mesh; do
  ref=$(pix $T/rtcl-$s-dynamic.ppm)
  for k in naive cyclic dynamic persistent wavefront; do
    o=$(pix $T/rtcl-561d019-$s-$k.ppm 2>/dev/null); n=$(pix $T/rtcl-$s-$k.ppm 2>/dev/null)
    echo "  $s $k: $o | $n  $([ "$o" = "$n" ] && echo same-as-old || echo CHANGED)  $([ "$n" = "$ref" ] && echo same-as-dynamic || echo differs-from-dynamic)"
  done
done
