#!/bin/bash
# GPU batch 61 (issue 26), for the next session with device time: rtcl against
# TinyBVH on the same primary rays once the program cache builds its binaries
# with the build options (f3ae66c). Batches 58-59 found every render whose
# program came from the cache 7-16 % slower (docs/results/multidevice); which
# of batches 45-56's rtcl figures were cached was not recorded. Here the same
# command as batch 56: programs built from source every run (RTCL_CACHE=0),
# then from a cache that a pass before filled. Each --stats under
# raw/ says build_cached. Outputs go into one tar (the device tool returns at
# most 8 files). Needs .gpu/peer (the peer's folder, ../shared/bench/tinybvh)
# and the binaries in .gpu/ as in docs/results/h100-batch7/README.md.
#   COMMIT=<commit> bash docs/results/h100-batch8/run61.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
T=$(mktemp -d)
cd tools
# fresh: built from source every run; fill: fills the cache (output dropped);
# cached: every program from the cache. WHICH=fresh|cached runs one of them.
for pass in ${WHICH:-fresh cached}; do
  for p in $([ $pass = cached ] && echo fill) $pass; do
    cache=1; [ $p = fresh ] && cache=0
    RTCL_CACHE=$cache RTCL_COMMIT=$COMMIT python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
      -o $T/peer-$p -r 10 -k persistent,dynamic,naive --meshes tetra:8,mount:8,mount:9,lake \
      2>&1 | tail -8
    echo "$p: $(grep -h -o '"build_cached": [a-z]*' $T/peer-$p/raw/*.json | sort | uniq -c | tr '\n' ' ')"
  done
  rm -rf $T/peer-fill
done
tar czf $OUT/batch61.tgz -C $T .
