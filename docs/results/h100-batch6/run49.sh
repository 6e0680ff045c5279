#!/bin/bash
# GPU batch 49 (issue 26): two more costs of rtcl's step against TinyBVH's, on
# the peer's primary-ray meshes, after batch 46 found rtcl's bare traversal
# 0.84x TinyBVH's on mount 8. One binary (.gpu/rtcl-x: 3cc00d3 plus
# run49-experiments.patch, batch 46's switches and two more):
#   RT_X_NOTIE      the nearest hit taken by distance only, without brute
#                   force's tie rule (the lower index at an equal distance)
#   RT_X_NOSPHERES  a leaf's code for triangles only (a scene of meshes has no
#                   leaf of spheres nor of references)
# persistent: as main, notie, nosph, both; naive with RT_X_HITONLY (nothing
# shaded): alone and with both. Three interleaved rounds of -r 20 (2000x2000),
# median kernel ms; images against main's.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread-x
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
declare -A O=([base]="" [notie]="-DRT_X_NOTIE" [nosph]="-DRT_X_NOSPHERES"
  [both]="-DRT_X_NOTIE -DRT_X_NOSPHERES" [hit]="-DRT_X_HITONLY"
  [hitboth]="-DRT_X_HITONLY -DRT_X_NOTIE -DRT_X_NOSPHERES")
declare -A K=([base]=persistent [notie]=persistent [nosph]=persistent [both]=persistent
  [hit]=naive [hitboth]=naive)
SCENES="tetra8 mount8 mount9 lake"
VARS="base notie nosph both hit hitboth"
for round in 1 2 3; do
  for s in $SCENES; do
    for v in $VARS; do
      RTCL_BUILD_OPTIONS="${O[$v]}" $G/rtcl-x -p $P -k ${K[$v]} -w 8x8 -s $T/$s-primary.json -r 20 -q \
        -o $T/$v-$s.pfm --stats $T/s.json
      echo "round $round $s $v kernel_ms $(grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1 | awk '{print $2}')"
    done
  done
done
for s in $SCENES; do
  for v in notie nosph both; do
    cmp -s $T/base-$s.pfm $T/$v-$s.pfm && echo "  $s $v: image identical to base's" || \
      python3 -c "import sys; n=2000*2000*12; a=open(sys.argv[1],'rb').read()[-n:]; b=open(sys.argv[2],'rb').read()[-n:]; print('  $s $v: image differs in', sum(a[i:i+12] != b[i:i+12] for i in range(0, n, 12)), 'pixels')" $T/base-$s.pfm $T/$v-$s.pfm
  done
done
