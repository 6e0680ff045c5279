#!/bin/bash
# GPU batch 46 (issue 26): where the rest of the gap to TinyBVH is. One binary
# (.gpu/rtcl-x: 3cc00d3 plus run46-experiments.patch, which adds RT_X_HITONLY:
# with one sample, the primary ray's closest hit only, t and the index stored,
# no shading, as a bare traversal kernel does) against the full tracer, on the
# peer's primary-ray meshes, kernels persistent, naive and dynamic; three
# interleaved rounds of -r 20 (2000x2000), median kernel ms. Then
# rtcl-peer-compare once more in the same session (into $OUT/peer).
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
SCENES="tetra8 mount8 mount9 lake"
VARS="persistent:base persistent:hit naive:base naive:hit dynamic:base dynamic:hit"
for round in 1 2 3; do
  for s in $SCENES; do
    for v in $VARS; do
      k=${v%:*}; x=${v#*:}; [ $x = hit ] && opt=-DRT_X_HITONLY || opt=""
      RTCL_BUILD_OPTIONS="$opt" $G/rtcl-x -p $P -k $k -w 8x8 -s $T/$s-primary.json -r 20 -q \
        -o $T/$k-$x-$s.pfm --stats $T/s.json
      echo "round $round $s $k $x kernel_ms $(grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1 | awk '{print $2}')"
    done
  done
done
cd tools && RTCL_COMMIT=$COMMIT python3 peer_compare.py ../.gpu/peer --rtcl ../.gpu/rtcl \
  -o $OUT/peer -r 10 -k persistent,dynamic,naive --meshes tetra:8,mount:8,mount:9,lake 2>&1 | tail -8
