#!/bin/bash
# GPU batch 15: instruction analysis, part two: SASS from the dumped PTX
# (trailing NULs stripped), and Nsight Compute on one launch (persistent,
# default scene and 2,000 balls), if ncu profiles OpenCL.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export PATH=/usr/local/cuda/bin:$PATH
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genscene.py --balls 2000 -o $T/r2000.json
for sc in paper60 r2000; do
  S=""; [ $sc != paper60 ] && S="-s $T/r2000.json"
  RTCL_CACHE=0 RTCL_DUMP_BINARY=$T/$sc.ptx $R -p $P -k persistent --size 64x64 $S -q -o $T/a.ppm
  tr -d '\000' < $T/$sc.ptx > $T/$sc-clean.ptx
  ptxas -arch=sm_90 -v -maxrregcount 80 -o $T/$sc.cubin $T/$sc-clean.ptx 2>&1 | tail -3 | sed "s/^/  $sc /"
  cuobjdump -sass $T/$sc.cubin > $OUT/persistent-$sc.sass; echo "  $sc sass lines: $(wc -l < $OUT/persistent-$sc.sass)"
  timeout 240 ncu --target-processes all -c 1 -k regex:persistent --section SpeedOfLight --section WarpStateStats --section Occupancy --section MemoryWorkloadAnalysis --section SchedulerStats --section InstructionStats --section LaunchStats $R -p $P -k persistent $S -q -o $T/n.ppm > $OUT/ncu-$sc.txt 2>&1
  echo "  ncu $sc rc $?: $(wc -l < $OUT/ncu-$sc.txt) lines"; head -5 $OUT/ncu-$sc.txt
done
