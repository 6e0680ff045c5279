#!/bin/bash
# GPU batch 34 (issue 25): SIMD efficiency measured on the H100 (inline PTX
# activemask in the counting build) beside the model (flops per pixel and the
# schedule map), for every kernel on the default scene, glass_mesh and the
# empty scene; the two ends (serial: 1/32; the empty scene, naive, every pixel
# one miss: 100 %); the instrumented images against the plain ones; kernel
# times of the plain render (-r 10) beside, to ask whether SIMD efficiency
# orders the kernels as time does.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
field() { python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); v=d
for k in sys.argv[2].split("."): v=v[k] if isinstance(v, dict) else v
print(v)' "$1" "$2"; }
echo "== the two ends"
$G/rtcl -p $P -k serial --size 64x64 -o $T/s.ppm --flops $T/s.npy --stats $T/s.json -q && \
  echo "  serial 64x64: measured $(field $T/s.json simd_efficiency_measured)"
$G/rtcl -p $P -k naive -w 32x1 -s scenes/empty.json --size 256x64 -o $T/e.ppm --flops $T/e.npy --stats $T/e.json -q && \
  echo "  empty, naive 32x1: measured $(field $T/e.json simd_efficiency_measured)"
echo "== kernels: measured, modelled, parallel efficiency, time"
for s in paper60 glass_mesh; do
  args=""; [ $s = glass_mesh ] && args="-s scenes/glass_mesh.json"
  for k in naive cyclic dynamic persistent wavefront; do
    map="--schedule-map $T/m.npy"; [ $k = wavefront ] && map=""
    $G/rtcl -p $P -k $k $args -o $T/i.ppm --work-map $T/w.npy $map --stats $T/c.json -q || echo "FAILED $k $s"
    $G/rtcl -p $P -k $k $args -o $T/p.ppm -q -r 10 --stats $T/t.json || echo "FAILED $k $s"
    same=$(cmp -s $T/i.ppm $T/p.ppm && echo same || echo DIFFERENT)
    echo "  $s $k: measured $(field $T/c.json simd_efficiency_measured); modelled $(field $T/c.json simd_efficiency_model 2>/dev/null || echo -); parallel $(field $T/c.json parallel_efficiency); kernel $(field $T/t.json kernel_ms) ms; instrumented image $same"
  done
done
echo "== the summary line, as printed"
$G/rtcl -p $P -k dynamic -o $T/x.ppm --work-map $T/w.npy --schedule-map $T/m.npy | grep simd
