#!/bin/bash
# GPU batch 40 (issue 26): the BVH builder's node cost against the peer's.
# rtcl tests 2.4x as many triangles per ray as TinyBVH's BVH_GPU on the SPD
# mount meshes and the lake (docs/results/h100-peer-tinybvh/counts): its SAH
# prices a node visit at 3 primitive tests (BVH_NODE_COST, tuned on spheres),
# TinyBVH at 1. Binaries built with -DBVH_NODE_COST=C -DBVH_MAX_LEAF=L
# (rtcl: 3, 8; n1l4, n1l8, n2l8), persistent kernel, 2000x2000: the peer's
# primary-ray scenes (the mesh alone, max_depth 0, no lights: tetra 8, mount
# 8 and 9, the lake) and Whitted scenes (the lake at depth 5, glass_mesh,
# the default scene); three interleaved rounds of -r 20 (kernel ms), then a
# counting run of each for the work per ray; images compared.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
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
  [lake]="-s $T/lake/lake-10.json --size 2000x2000" [glass_mesh]="-s scenes/glass_mesh.json --size 2000x2000"
  [paper60]="--size 2000x2000")
SCENES="tetra8-primary mount8-primary mount9-primary lake-primary lake glass_mesh paper60"
BINS="rtcl rtcl-n1l4 rtcl-n1l8 rtcl-n2l8"
for round in 1 2 3; do
  for s in $SCENES; do
    for b in $BINS; do
      $G/$b -p $P -k persistent ${S[$s]} -r 20 -q -o $T/$b-$s.ppm --stats $T/s.json
      echo "round $round $s $b kernel_ms $(grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1 | awk '{print $2}')"
    done
  done
done
for s in $SCENES; do
  for b in $BINS; do
    $G/$b -p $P -k persistent ${S[$s]} -q -o $T/c.ppm --flops $T/f.npy --stats $T/c.json
    echo "counted $s $b $(python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print("node/ray %.2f leaf/ray %.2f tests/ray %.2f rays %d bytes/tri %s nodes %d build_ms %.0f" % (d["node_visits_per_ray"], d["leaf_visits_per_ray"], d["primitive_tests_per_ray"], d["rays"], d.get("bytes_per_triangle"), d["bvh"]["nodes"], d["bvh"]["build_ms"]))' $T/c.json)"
    cmp -s $T/rtcl-$s.ppm $T/$b-$s.ppm && echo "  $s $b: image identical to rtcl's" || echo "  $s $b: IMAGE DIFFERS"
  done
done
