#!/bin/bash
# The session's last lease on four GPUs (nvidia-h100-x4):
#   1. issue 43: docs/results/h100x4/run106-frames.sh (--frames 0:15 and 0:5
#      on one GPU and four, each RTCL_FRAMES_READ way, two rounds);
#   2. issue 41: docs/results/h100-paths-study/run-fetch.sh on GPU 0 (path
#      regeneration's counter schemes item, group, subgroup, with --fetch
#      group's blocks now in global memory: every image against dynamic's).
# Binaries: $B (default .gpu/b106: rtcl and rtcl-meshread of COMMIT, make
# OIIO=0 MPI=0 BUILD=build-gpu BIN=...), .gpu/lib. From the repository root:
#   COMMIT=<commit> OUT=<folder> bash docs/results/h100x4/run106-all.sh [1] [2]
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b106}
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$B/rtcl-meshread
mkdir -p $OUT
PARTS=" ${*:-1 2} "; part() { [[ $PARTS == *" $1 "* ]]; }
part 1 && {
echo "== 1. run106-frames.sh ($(date -u +%T))"
mkdir -p $OUT/p43; OUT=$OUT/p43 B=$B COMMIT=$COMMIT timeout 240 bash docs/results/h100x4/run106-frames.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; grep -vE "^GPU|^commit" $OUT/p43/run106-frames.txt | cut -c1-330 | tail -40
(cd $OUT && tar czf p43.tgz p43 && rm -rf p43)
}
part 2 && {
echo "== 2. run-fetch.sh ($(date -u +%T))"
mkdir -p $OUT/p41f; OUT=$OUT/p41f B=$B COMMIT=$COMMIT timeout 200 bash docs/results/h100-paths-study/run-fetch.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; grep -E "round|DIFF|FAIL" $OUT/p41f/fetch.txt
(cd $OUT && tar czf p41f.tgz p41f && rm -rf p41f)
}
echo "== end ($(date -u +%T))"; ls -la $OUT
