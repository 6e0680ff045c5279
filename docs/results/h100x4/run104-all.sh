#!/bin/bash
# One lease on four GPUs (nvidia-h100-x4) after batch 103's changes:
#   1. issue 43: docs/results/h100x4/run99.sh whole (the default scene at
#      2048 spp, the lake at 256 spp, the path-traced box by -k dynamic and
#      -k wavefront over 1, 2 and 4 GPUs in one process and over 1, 2 and 4
#      MPI ranks; --frames 0:15 and 0:5), one GPU the baseline in the same
#      call, now with RTCL_MPI_SUMS's default host-ptr: the one batch the
#      issue's table asks for;
#   2. issue 41: the stages form's new default pool (2^22 paths on a GPU) on
#      GPU 0, against the bounce form and dynamic: cornell and materials_path
#      at 1024x1024, 64 spp, -r 3, the images compared with dynamic's.
# Binaries: $B (default .gpu/b104: rtcl, rtcl-meshread of COMMIT with make
# OIIO=0 MPI=0 BUILD=build-gpu BIN=...; rtcl-mpi with make OIIO=0),
# .gpu/lib, .gpu/ompi. From the repository root:
#   COMMIT=<commit> OUT=<folder> bash docs/results/h100x4/run104-all.sh [1] [2]
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b104}
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$B/rtcl-meshread
mkdir -p $OUT
PARTS=" ${*:-1 2} "; part() { [[ $PARTS == *" $1 "* ]]; }
part 1 && {
echo "== 1. run99.sh ($(date -u +%T))"
mkdir -p $OUT/p43; OUT=$OUT/p43 B=$B COMMIT=$COMMIT timeout 420 bash docs/results/h100x4/run99.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; grep -E "^[A-Z]-[0-9]-[0-9]:|^m[A-Z][0-9]-[0-9]:|^fr|DIFFERS|frames the same" $OUT/p43/run99.txt |
  sed -E 's/; (busy|[0-9]+ frames busy).*//' | cut -c1-230
(cd $OUT && tar czf p43.tgz p43 && rm -rf p43)
}
part 2 && {
echo "== 2. the stages form's default pool ($(date -u +%T))"
T=$(mktemp -d)
for sc in cornell materials_path; do
  for run in dynamic bounce stages; do
    case $run in
      dynamic) args="-k dynamic" ;;
      bounce) args="-k wavefront --wavefront-form bounce" ;;
      stages) args="-k wavefront --wavefront-form stages" ;;
    esac
    timeout 60 $B/rtcl -p 0 -d 0 scenes/$sc.json $args --size 1024x1024 --spp 64 -r 3 -q -o $T/$run.pfm --stats $OUT/$sc-$run.json ||
      echo "$sc $run FAILED"
    python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); st = d.get('wavefront_stages') or {}
print('$sc $run: %.2f ms (rounds %.2f-%.2f)' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max']),
      'pool %d' % st['paths_in_flight'] if st else '')" $OUT/$sc-$run.json
    [ $run = dynamic ] || { cmp -s $T/$run.pfm $T/dynamic.pfm && echo "  same bytes as dynamic" || echo "  IMAGE DIFFERS from dynamic"; }
  done
done
rm -rf $T
}
echo "== end ($(date -u +%T))"; ls -la $OUT
