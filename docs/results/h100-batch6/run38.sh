#!/bin/bash
# GPU batch 38 (issue 25 item 5): a lane-aware schedule, refill
# (cl/persistent.cl built with -DRTCL_REFILL through RTCL_BUILD_OPTIONS): each
# work-item steps its pixel one intersection at a time and fetches its next
# pixel the moment it is done, instead of waiting for its warp's longest pixel.
# Against the persistent kernel at rtcl's default geometry, on the default
# scene, the lake and glass_mesh at 2000x2000, --accel bvh: three interleaved
# rounds of -r 20 (lake -r 10), kernel ms from --stats; one counting run each
# for the measured SIMD efficiency; images compared byte for byte.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
R=$PWD/.gpu/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
declare -A SCENE=([paper60]="" [lake]="-s $T/lake/lake-10.json" [glass_mesh]="-s scenes/glass_mesh.json")
declare -A REP=([paper60]=20 [lake]=10 [glass_mesh]=20)
ms() { grep -o '"kernel_ms": [0-9.]*' $1 | head -1 | awk '{print $2}'; }
for round in 1 2 3; do
  for s in paper60 lake glass_mesh; do
    for v in persistent refill; do
      [ $v = refill ] && opt=-DRTCL_REFILL || opt=
      RTCL_BUILD_OPTIONS="$opt" $R -p $P -k persistent ${SCENE[$s]} --size 2000x2000 --accel bvh \
        -r ${REP[$s]} -q -o $T/$v-$s.ppm --stats $T/s.json
      echo "round $round $s $v kernel_ms $(ms $T/s.json)"
    done
  done
done
for s in paper60 lake glass_mesh; do
  for v in persistent refill; do
    [ $v = refill ] && opt=-DRTCL_REFILL || opt=
    RTCL_BUILD_OPTIONS="$opt" $R -p $P -k persistent ${SCENE[$s]} --size 2000x2000 --accel bvh \
      -q -o $T/c-$v-$s.ppm --flops $T/f.npy --stats $T/c.json
    echo "counted $s $v $(tr -d '\n ' < $T/c.json | grep -o '"simd_efficiency_measured":{[^}]*}') $(grep -o '"gflop": [0-9.]*' $T/c.json)"
  done
  cmp $T/persistent-$s.ppm $T/refill-$s.ppm && echo "$s: images identical" || echo "$s: IMAGES DIFFER"
  cmp $T/c-persistent-$s.ppm $T/persistent-$s.ppm && echo "$s: counting image identical" || echo "$s: COUNTING IMAGE DIFFERS"
done
