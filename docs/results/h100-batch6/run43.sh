#!/bin/bash
# GPU batch 43 (issue 26): triangles in BVH leaf order with their vertex
# positions inline (48 bytes each after the references; a leaf of triangles a
# range of them, RT_LEAF_TRIANGLES), the candidate docs/bvh.md names: one
# dependent load instead of three (reference, index word, vertices). Built
# from commit 5d015c4 of an experiment clone (the patch is
# run43-inline-triangles.patch) as .gpu/rtcl-inline, against .gpu/rtcl
# (f4fe5ee's code, 31877fb's BVH). Persistent, 2000x2000, the peer's
# primary-ray scenes and Whitted scenes, three interleaved rounds of -r 20,
# then a counting run of each; images compared.
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
BINS="rtcl rtcl-inline"
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
