#!/bin/bash
# BVH against brute force: median of 20 timed launches after a warm-up (OpenCL
# profiling events), 2000x2000, max depth 5, -k dynamic -w 8x8 unless named.
P=${P:-1}
echo "commit: $COMMIT"
echo "command: ./rtcl -p $P -k KERNEL -r 20 [-s SCENE] --accel ACCEL --stats S.json"
./rtcl --list-devices | grep -A1 NVIDIA
t() { # label, args...
  local label=$1; shift
  ./rtcl -p $P -r 20 --stats /tmp/st.json -q "$@" || return
  echo "$label $(grep -o '"kernel_ms": [0-9.]*' /tmp/st.json | head -1) $(grep -o '"scene_in_local_memory": [a-z]*' /tmp/st.json) $(grep -o '"nodes": [0-9]*' /tmp/st.json) $(grep -o '"depth": [0-9]*' /tmp/st.json) $(grep -o '"sah_cost": [0-9.]*' /tmp/st.json) $(grep -o '"build_ms": [0-9.]*' /tmp/st.json)"
}
for sc in paper60 r60 r400 r2000 r20000; do
  if [ $sc = paper60 ]; then S=""; else S="-s $sc.json"; fi
  t "$sc none" -k dynamic $S --accel none -o /tmp/$sc-none.ppm
  t "$sc bvh " -k dynamic $S -o /tmp/$sc-bvh.ppm
  cmp -s /tmp/$sc-none.ppm /tmp/$sc-bvh.ppm && echo "  $sc: bvh image byte-identical to none" || echo "  $sc: bvh image DIFFERS from none"
  ./rtcl -p $P -k dynamic $S --flops /tmp/f.npy --stats /tmp/st2.json -o /tmp/x.ppm -q
  echo "  $sc counting run (bvh): $(grep -o '"node_visits_per_ray": [0-9.]*' /tmp/st2.json) $(grep -o '"rays": [0-9]*' /tmp/st2.json) $(grep -o '"total_flops": [0-9]*' /tmp/st2.json) $(grep -o '"parallel_efficiency": [0-9.]*' /tmp/st2.json)"
done
for k in naive cyclic persistent wavefront; do
  t "paper60 -k $k none" -k $k --accel none -o /tmp/k-none.ppm
  t "paper60 -k $k bvh " -k $k -o /tmp/k-bvh.ppm
  cmp -s /tmp/k-none.ppm /tmp/k-bvh.ppm && echo "  identical" || echo "  DIFFERS"
done
