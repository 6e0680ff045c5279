#!/bin/bash
# GPU batch 32: batch 31's differences, with controls. Per-work-item flops of
# dynamic, persistent and the wavefront depend on which work-item took which
# chunk (or ray) at run time, and glass_mesh's wavefront image differed: here
# each binary (41af480 and $COMMIT) renders twice, so a difference between two
# runs of one binary shows what is nondeterministic; the flop totals (rays,
# flops, node visits: the sidecar's) must agree whatever the schedule.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 41af480 (rtcl-41af480)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
same() { cmp -s "$1" "$2" && echo same || echo DIFFERENT; }
totals() { python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(d["total_flops"], d["rays"], d["node_visits"])' "$1"; }
for s in paper60 glass_mesh; do
  args=""; [ $s = glass_mesh ] && args="-s scenes/glass_mesh.json"
  for k in dynamic persistent wavefront; do
    for b in rtcl-41af480 rtcl; do
      for n in 1 2; do
        $G/$b -p $P -k $k $args -o $T/$b-$n.ppm -q --flops $T/$b-$n.npy || echo "FAILED $b $k $s"
      done
    done
    echo "  $s $k: image old/old $(same $T/rtcl-41af480-1.ppm $T/rtcl-41af480-2.ppm)," \
      "new/new $(same $T/rtcl-1.ppm $T/rtcl-2.ppm), old/new $(same $T/rtcl-41af480-1.ppm $T/rtcl-1.ppm);" \
      "flops per item old/old $(same $T/rtcl-41af480-1.npy $T/rtcl-41af480-2.npy)," \
      "old/new $(same $T/rtcl-41af480-1.npy $T/rtcl-1.npy)"
    echo "    totals (flops rays node_visits): old $(totals $T/rtcl-41af480-1.npy.json) / $(totals $T/rtcl-41af480-2.npy.json), new $(totals $T/rtcl-1.npy.json) / $(totals $T/rtcl-2.npy.json)"
  done
done
# The wavefront against the single-pass kernels on glass_mesh, each binary.
for b in rtcl-41af480 rtcl; do
  for k in naive wavefront; do $G/$b -p $P -k $k -s scenes/glass_mesh.json -o $T/gm-$b-$k.ppm -q; done
  echo "  glass_mesh $b: wavefront against naive $(same $T/gm-$b-naive.ppm $T/gm-$b-wavefront.ppm)"
  python3 - $T/gm-$b-naive.ppm $T/gm-$b-wavefront.ppm <<'PY'
import sys
a, b = (open(p, 'rb').read() for p in sys.argv[1:3])
diff = sum(x != y for x, y in zip(a, b))
print(f"    bytes that differ: {diff} of {len(a)}")
PY
done
