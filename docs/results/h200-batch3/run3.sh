#!/bin/bash
# GPU batch 3: one image on the GPU and the 16-core CPU with the adaptive
# dispenser (issue 13), against the GPU alone; with the BVH (default).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
R=$PWD/.gpu/rtcl
T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L; nproc
P=$($R --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($R --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "nvidia platform $P, pocl platform $C"
S="--spp 1024 -k dynamic"
echo "== CPU alone, --spp 16"; $R -p $C --spp 16 -k dynamic -o $T/c.ppm | grep -E "^time"
for rep in 1 2 3; do
  echo "== round $rep"
  printf "GPU alone: "; $R -p $P $S -o $T/g.ppm --stats $OUT/gpu$rep.json | grep -E "^time"
  echo "GPU+CPU adaptive:"; $R --devices $P:0,$C:0 $S -o $T/gc.ppm --stats $OUT/gpucpu$rep.json | grep -vE "^(output|kernel|image|samples)"
done
echo "== GPU+CPU adaptive without the reserved core (POCL_MAX_PTHREAD_COUNT=16)"
POCL_MAX_PTHREAD_COUNT=16 $R --devices $P:0,$C:0 $S -o $T/gc16.ppm | grep -vE "^(output|kernel|image|samples)"
echo "== GPU+CPU -r 3 (rates carried over frames)"
$R --devices $P:0,$C:0 $S -r 3 -o $T/gcr.ppm | grep -vE "^(output|kernel|image|samples)"
echo "== GPU+CPU, 32-row bands (--piece-rows 32)"
$R --devices $P:0,$C:0 $S --piece-rows 32 -o $T/gcb.ppm | grep -vE "^(output|kernel|image|samples)"
cmp -l $T/g.ppm $T/gc.ppm | wc -l | xargs echo "bytes differing GPU vs GPU+CPU:"
python3 - $T/g.ppm $T/gc.ppm <<'PY'
import sys, numpy as np
def rd(p):
    b = open(p, 'rb').read(); i = 0; vals = []
    while len(vals) < 4:
        while b[i:i+1].isspace(): i += 1
        if b[i:i+1] == b'#':
            i = b.index(b'\n', i) + 1; continue
        j = i
        while not b[j:j+1].isspace(): j += 1
        vals.append(b[i:j]); i = j
    w, h = int(vals[1]), int(vals[2])
    return np.frombuffer(b[i+1:i+1+w*h*3], np.uint8).reshape(h, w, 3).astype(int)
a, b = rd(sys.argv[1]), rd(sys.argv[2]); d = abs(a - b)
print("max byte difference", d.max(), "pixels off by > 2/255:", (d.max(axis=2) > 2).mean() * 100, "%")
PY
