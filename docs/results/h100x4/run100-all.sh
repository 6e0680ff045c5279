#!/bin/bash
# The session's last device call (four H100s, nvidia-h100-x4), one lease for
# three issues, each part on its own clock and results folder:
#   1. issue 43: docs/results/h100x4/run100.sh (the box with -k dynamic and
#      -k wavefront over 1/2/4 GPUs and MPI ranks; --frames);
#   2. issue 41: docs/results/h100-stages/run101.sh on GPU 0 (the stages form
#      after wave41b against the bounce form and dynamic, same call);
#   3. issue 41: the paths study's counting runs of every schedule but
#      dynamic's (batch 99 has those) on cornell and materials_path
#      (COUNT_ONLY=1 ONLY=...), and each schedule's registers and spills;
#   4. issue 42: rtcl-rays on PoCL against TinyBVH's CPU traversals on the
#      host's cores (.gpu/inc99, 0849869's rtcl-rays), capped.
# Binaries: .gpu/b100 (rtcl, rtcl-meshread, rtcl-mpi of COMMIT; make OIIO=0
# MPI=0 BUILD=build-gpu BIN=...; rtcl-mpi with make OIIO=0), .gpu/lib,
# .gpu/ompi, .gpu/inc99. From the repository root:
#   COMMIT=<commit> bash docs/results/h100x4/run100-all.sh
set -u
ROOT=$PWD; B=$ROOT/.gpu/b100
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$B/rtcl-meshread
mkdir -p $OUT/p43 $OUT/p41s $OUT/p41c
echo "== 1. run100.sh ($(date -u +%T))"
OUT=$OUT/p43 B=$B COMMIT=$COMMIT timeout 200 bash docs/results/h100x4/run100.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; (cd $OUT && tar czf p43.tgz p43 && rm -rf p43)
echo "== 2. run101.sh ($(date -u +%T))"
OUT=$OUT/p41s B=$B COMMIT=$COMMIT timeout 100 bash docs/results/h100-stages/run101.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; tail -40 $OUT/p41s/log.txt
echo "== 3. counting runs and registers ($(date -u +%T))"
OUT=$OUT/p41c B=$B COMMIT=$COMMIT COUNT_ONLY=1 ONLY="cornell materials_path" \
  COUNTED="naive persistent persistent-regen-item persistent-regen-subgroup wavefront-bounce wavefront-stages" \
  BUDGET=80 MITSUBA=0 timeout 100 bash docs/results/h100-paths-study/run.sh > /dev/null 2>&1
echo "exit $? ($(date -u +%T))"; tail -15 $OUT/p41c/log.txt
for o in "-k naive" "-k persistent" "-k persistent --regenerate --fetch item" "-k persistent --regenerate --fetch subgroup" "-k wavefront" "-k wavefront --wavefront-form stages"; do
  echo "$o: $(RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose timeout 20 $B/rtcl -p 0 -d 0 $o scenes/materials_path.json --size 64x64 --spp 2 -v -o /tmp/v.pfm 2>&1 |
    grep -oE "entry function '[a-z_0-9]+'|[0-9]+ bytes spill stores, [0-9]+ bytes spill loads|Used [0-9]+ registers" | tr '\n' ' ' | sed "s/entry function/\n    /g")"
done | tee $OUT/p41c/registers.txt
(cd $OUT && tar czf p41.tgz p41s p41c && rm -rf p41s p41c)
echo "== 4. incoherent rays on the CPU ($(date -u +%T))"
OUT=$OUT/p42 CPU_CAP=35 CPU_ROUNDS=2 timeout 120 bash .gpu/inc99/run.sh cpu 2>&1 | grep -E "x \(rounds|exit|^\| (mount|tetra|lake)"
echo "== end ($(date -u +%T))"
ls -la $OUT $OUT/p42
