#!/bin/bash
# One lease on four H100s (nvidia-h100-x4) for three issues, each part on its
# own clock and results folder, archived as it ends:
#   1. issue 43: docs/results/h100x4/run102.sh: the path-traced box over 1
#      and 4 MPI ranks, each of the three ways RTCL_MPI_SUMS names;
#   2. issue 41: docs/results/h100-stages/run101.sh on GPU 0 with POOLS from
#      256 K to 8 M paths in flight (the stages form's default pool);
#   3. issue 41: the stages form's counting runs (SIMD efficiency of each
#      stage kernel) on cornell and materials_path (COUNT_ONLY=1);
#   4. issue 41: the studio scene's rtcl rows and Mitsuba's (ONLY=studio_path,
#      one round: the row batch 99 could not map).
#   5. issue 42: rtcl-rays on PoCL against TinyBVH's CPU traversals on the
#      host's cores (bash .gpu/inc99/run.sh cpu =
#      docs/results/h100-incoherent/run99.sh cpu), last: it needs a quiet host.
# The arguments name the parts (default all); what is carried must stay
# under the tool's 64 MiB, so part 4 (Mitsuba, .gpu-pt/mi) and 5
# (.gpu/inc99) go in a second call: run103-all.sh 1 2 3, then 4 5.
# Binaries: $B (default .gpu/b103: rtcl, rtcl-meshread of COMMIT with make
# OIIO=0 MPI=0 BUILD=build-gpu BIN=...; rtcl-mpi with make OIIO=0),
# .gpu/lib, .gpu/ompi, .gpu-pt/mi. From the repository root:
#   COMMIT=<commit> OUT=<folder> bash docs/results/h100x4/run103-all.sh
set -u
ROOT=$PWD; B=${B:-$ROOT/.gpu/b103}
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$B/rtcl-meshread
mkdir -p $OUT
PARTS=" ${*:-1 2 3 4 5} "; part() { [[ $PARTS == *" $1 "* ]]; }
part 1 && {
echo "== 1. run102.sh ($(date -u +%T))"
mkdir -p $OUT/p43; OUT=$OUT/p43 B=$B COMMIT=$COMMIT timeout 150 bash docs/results/h100x4/run102.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; tail -6 $OUT/p43/run102.txt; (cd $OUT && tar czf p43.tgz p43 && rm -rf p43)
}

part 2 && {
echo "== 2. run101.sh, pools 256K-8M ($(date -u +%T))"
mkdir -p $OUT/p41s; OUT=$OUT/p41s B=$B COMMIT=$COMMIT POOLS="262144 1048576 2097152 4194304 8388608" \
  timeout 120 bash docs/results/h100-stages/run101.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; grep -E "^==|kernel_ms|image" $OUT/p41s/log.txt
(cd $OUT && tar czf p41s.tgz p41s && rm -rf p41s)
}

part 3 && {
echo "== 3. the stages form's counting runs ($(date -u +%T))"
mkdir -p $OUT/p41c; OUT=$OUT/p41c B=$B COMMIT=$COMMIT SIZE=${C_SIZE:-1024x1024} SPP=${C_SPP:-64} COUNT_ONLY=1 ONLY="cornell materials_path" COUNTED="wavefront-stages" \
  BUDGET=${C_BUDGET:-80} MITSUBA=0 timeout ${C_CAP:-100} bash docs/results/h100-paths-study/run.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; tail -4 $OUT/p41c/log.txt
(cd $OUT && tar czf p41c.tgz p41c && rm -rf p41c)
}

part 4 && {
echo "== 4. studio_path: rtcl's schedules and Mitsuba ($(date -u +%T))"
mkdir -p $OUT/p41m; OUT=$OUT/p41m B=$B COMMIT=$COMMIT ONLY=studio_path ROUNDS=1 COUNTED=none BUDGET=150 MITSUBA_S=120 \
  timeout 280 bash docs/results/h100-paths-study/run.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; grep -E "^rtcl|mitsuba|Mitsuba|same|DIFF|FAIL" $OUT/p41m/log.txt | head -30
(cd $OUT && tar czf p41m.tgz p41m && rm -rf p41m)
}

part 5 && {
echo "== 5. incoherent rays on the CPU ($(date -u +%T))"
mkdir -p $OUT/p42; OUT=$OUT/p42 CPU_CAP=${CPU_CAP:-110} CPU_ROUNDS=2 timeout 360 bash .gpu/inc99/run.sh cpu 2>&1 | grep -E "x \\(rounds|exit|^\\| (mount|tetra|lake)"
}
echo "== end ($(date -u +%T))"; ls -la $OUT
