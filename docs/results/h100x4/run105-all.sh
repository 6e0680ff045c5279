#!/bin/bash
# One lease on four GPUs (nvidia-h100-x4), the session's last:
#   1. issue 43: docs/results/h100x4/run105.sh (--frames 0:15 and 0:5 on one
#      GPU and on four, two rounds);
#   2. issue 41: docs/results/h100-paths-study/replay.sh on GPU 0 (schedule
#      maps of the pixel-taking schedules on paths, for tools/schedule_replay.py);
#   3. issue 41: docs/results/h100-paths-study/run-fetch.sh on GPU 0 (path
#      regeneration's three counter schemes, item, group and subgroup).
# Binaries: $B (default .gpu/b105: rtcl and rtcl-meshread of COMMIT, make
# OIIO=0 MPI=0 BUILD=build-gpu BIN=...), .gpu/lib. From the repository root:
#   COMMIT=<commit> OUT=<folder> bash docs/results/h100x4/run105-all.sh [1] [2] [3]
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b105}
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$B/rtcl-meshread
mkdir -p $OUT
PARTS=" ${*:-1 2 3} "; part() { [[ $PARTS == *" $1 "* ]]; }
part 1 && {
echo "== 1. run105.sh ($(date -u +%T))"
mkdir -p $OUT/p43; OUT=$OUT/p43 B=$B COMMIT=$COMMIT timeout 200 bash docs/results/h100x4/run105.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; grep -E "^fr|frames|x$" $OUT/p43/run105.txt | cut -c1-400
(cd $OUT && tar czf p43.tgz p43 && rm -rf p43)
}
part 2 && {
echo "== 2. replay.sh ($(date -u +%T))"
mkdir -p $OUT/p41r; OUT=$OUT/p41r B=$B COMMIT=$COMMIT timeout 120 bash docs/results/h100-paths-study/replay.sh 2>&1 | tail -8
echo "exit $? ($(date -u +%T))"; (cd $OUT && tar czf p41r.tgz p41r && rm -rf p41r)
}
part 3 && {
echo "== 3. run-fetch.sh ($(date -u +%T))"
mkdir -p $OUT/p41f; OUT=$OUT/p41f B=$B COMMIT=$COMMIT timeout 240 bash docs/results/h100-paths-study/run-fetch.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; grep -E "round|DIFF|FAIL" $OUT/p41f/fetch.txt
(cd $OUT && tar czf p41f.tgz p41f && rm -rf p41f)
}
echo "== end ($(date -u +%T))"; ls -la $OUT
