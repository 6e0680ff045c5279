#!/bin/bash
# GPU batch 44 (issue 26): cheaper traversal steps, one binary (.gpu/rtcl-x:
# main at 3cc00d3 plus experiment macros, the patch run44-experiments.patch)
# and the variants chosen by RTCL_BUILD_OPTIONS or an option:
#   base   as main
#   s4     RT_X_STACK4: 4-byte traversal stack entries instead of 8
#   ls     s4 with the stack in __local memory (entry k of a work-item at
#          k*64 + its local id: consecutive lanes, consecutive banks)
#   t1     RT_X_TRI1: the triangle test with one branch at the end
#   lst1   ls and t1
#   r96    -cl-nv-maxrregcount=96 (rtcl's cap is 80)
#   b4     --batch 4 (4 pixels a fetch of the persistent counter)
# Persistent -w 8x8, 2000x2000, three interleaved rounds of -r 20, median
# kernel ms; every image compared with base's.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl-x --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
for m in "tetra 8" "mount 8" "mount 9" "lake"; do
  set -- $m
  python3 tools/genbench.py $1 -o $T/$1${2:-} ${2:+--size $2 --triangles ply} > /dev/null
done
python3 - $T <<'PY'
import json, pathlib, sys
T = pathlib.Path(sys.argv[1])
for folder in ("tetra8", "mount8", "mount9", "lake"):
    (path,) = (T / folder).glob("*.json")
    scene = json.loads(path.read_text())
    mesh = dict(scene["meshes"][0]); mesh["file"] = str((T / folder / mesh["file"]).resolve())
    primary = {"format": "rtcl-scene", "version": 2, "camera": scene["camera"],
               "materials": scene.get("materials", {}), "image": {"width": 2000, "height": 2000},
               "background": [1, 0, 1], "max_depth": 0, "lights": [], "meshes": [mesh]}
    (T / f"{folder}-primary.json").write_text(json.dumps(primary))
PY
declare -A S=([tetra8-primary]="-s $T/tetra8-primary.json" [mount8-primary]="-s $T/mount8-primary.json"
  [mount9-primary]="-s $T/mount9-primary.json" [lake-primary]="-s $T/lake-primary.json"
  [lake]="-s $T/lake/lake-10.json --size 2000x2000" [paper60]="--size 2000x2000")
declare -A O=([base]="" [s4]="-DRT_X_STACK4" [ls]="-DRT_X_STACK4 -DRT_X_LOCALSTACK -DRT_X_WG=64"
  [t1]="-DRT_X_TRI1" [lst1]="-DRT_X_STACK4 -DRT_X_LOCALSTACK -DRT_X_WG=64 -DRT_X_TRI1"
  [r96]="-cl-nv-maxrregcount=96" [b4]="")
declare -A A=([b4]="--batch 4")
SCENES="tetra8-primary mount8-primary mount9-primary lake-primary lake paper60"
VARS="base s4 ls t1 lst1 r96 b4"
echo "== registers (-cl-nv-verbose, lake at depth 5, 64x64)"
for v in $VARS; do
  RTCL_CACHE=0 RTCL_BUILD_OPTIONS="-cl-nv-verbose ${O[$v]}" $G/rtcl-x -p $P -k persistent -w 8x8 \
    -s $T/lake/lake-10.json --size 64x64 -v -o $T/v.ppm 2>&1 | grep -i "registers\|spill\|stack frame" | sed "s/^/$v: /" | head -4
done
for round in 1 2 3; do
  for s in $SCENES; do
    for v in $VARS; do
      RTCL_BUILD_OPTIONS="${O[$v]}" $G/rtcl-x -p $P -k persistent -w 8x8 ${A[$v]:-} ${S[$s]} -r 20 -q \
        -o $T/$v-$s.ppm --stats $T/s.json
      echo "round $round $s $v kernel_ms $(grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1 | awk '{print $2}')"
    done
  done
done
for s in $SCENES; do
  for v in $VARS; do
    cmp -s $T/base-$s.ppm $T/$v-$s.ppm && echo "  $s $v: image identical to base's" || echo "  $s $v: IMAGE DIFFERS"
  done
done
