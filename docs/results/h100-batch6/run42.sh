#!/bin/bash
# GPU batch 42 (issue 26 step 1): registers and spills of rtcl's persistent
# kernel as NVIDIA's compiler reports them (-cl-nv-verbose, printed with -v),
# on a mesh scene (the lake, primary rays and depth 5) and on the default
# scene, at the commit measured.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
R=$PWD/.gpu/rtcl
echo "commit: $COMMIT"; nvidia-smi -L
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
for s in "default" "lake:-s $T/lake/lake-10.json" "lake-depth0:-s $T/lake/lake-10.json --depth 0"; do
  name=${s%%:*}; args=${s#*:}; [ "$name" = default ] && args=
  echo "== $name"
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $R -p $P -k persistent $args --size 256x256 -v \
    -o $T/x.ppm 2>&1 | grep -iE "registers|spill|stack frame" | sort -u | head -12
done
