#!/bin/bash
# GPU batch 14: instruction analysis. The PTX NVIDIA's OpenCL builds for the
# default scene (block in __local) and 2,000 balls (__global), dynamic and
# persistent; SASS through ptxas/cuobjdump where the machine has them.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; R=$G/rtcl; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genscene.py --balls 2000 -o $T/r2000.json
for t in ptxas cuobjdump nvdisasm ncu nsys; do printf "%s: %s\n" $t "$(command -v $t || ls /usr/local/cuda*/bin/$t 2>/dev/null || echo none)"; done
ls /usr/local/nvidia/bin 2>/dev/null | head; ls -d /usr/local/cuda* 2>/dev/null
for k in dynamic persistent; do
  RTCL_CACHE=0 RTCL_DUMP_BINARY=$OUT/$k-paper60.ptx RTCL_BUILD_OPTIONS=-cl-nv-verbose $R -p $P -k $k --size 64x64 -v -o $T/a.ppm 2>&1 | grep -iE "registers|spill|options|local" | sed 's/^/  paper60 '$k' /'
  RTCL_CACHE=0 RTCL_DUMP_BINARY=$OUT/$k-r2000.ptx RTCL_BUILD_OPTIONS=-cl-nv-verbose $R -p $P -k $k --size 64x64 -s $T/r2000.json -v -o $T/a.ppm 2>&1 | grep -iE "registers|spill|options|local" | sed 's/^/  r2000 '$k' /'
done
PTXAS=$(command -v ptxas || ls /usr/local/cuda*/bin/ptxas 2>/dev/null | head -1)
if [ -n "$PTXAS" ]; then
  for f in $OUT/persistent-paper60.ptx $OUT/persistent-r2000.ptx; do
    $PTXAS -arch=sm_90 -v -maxrregcount 80 -o $T/x.cubin $f 2>&1 | tail -4
    CUO=$(command -v cuobjdump || ls /usr/local/cuda*/bin/cuobjdump 2>/dev/null | head -1)
    [ -n "$CUO" ] && $CUO -sass $T/x.cubin > ${f%.ptx}.sass && wc -l ${f%.ptx}.sass
  done
fi
ls -la $OUT
