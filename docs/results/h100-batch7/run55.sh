#!/bin/bash
# GPU batch 55 (issue 26): scenes without lights, compiled without the light
# loop (an experiment switch, -DRTCL_NO_LIGHTS through RTCL_BUILD_OPTIONS;
# shading_next_light returns false, so the shadow-ray path is dead code).
# Primary rays of TinyBVH's comparison (max_depth 0, no lights; tetra 8,
# mount 8, the lake), persistent -w 8x8, 2000x2000, three interleaved rounds of
# -r 20; images compared.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl-nl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
python3 tools/genbench.py tetra --size 8 -o $T/tetra > /dev/null
python3 tools/genbench.py mount --size 8 -o $T/mount > /dev/null
ls $T/tetra $T/mount
python3 - $T <<'PY'
import json, pathlib, sys
T = pathlib.Path(sys.argv[1])
for name, path in [("lake", T / "lake" / "lake-10.json"), ("tetra", next((T / "tetra").glob("*.json"))),
                   ("mount", next((T / "mount").glob("*.json")))]:
    scene = json.loads(path.read_text())
    mesh = dict(scene["meshes"][0]); mesh["file"] = str((path.parent / mesh["file"]).resolve())
    primary = {"format": "rtcl-scene", "version": 2, "camera": scene["camera"],
               "materials": scene.get("materials", {}), "image": {"width": 2000, "height": 2000},
               "background": [1, 0, 1], "max_depth": 0, "lights": [], "meshes": [mesh]}
    (T / f"{name}-primary.json").write_text(json.dumps(primary))
PY
for round in 1 2 3; do
  for s in tetra mount lake; do
    for v in plain nolights; do
      [ $v = nolights ] && export RTCL_BUILD_OPTIONS=-DRTCL_NO_LIGHTS || unset RTCL_BUILD_OPTIONS
      $G/rtcl-nl -p $P -k persistent -w 8x8 -s $T/$s-primary.json -r 20 -q -o $T/$v-$s.ppm --stats $T/s.json
      echo "round $round $s $v kernel_ms $(grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1 | awk '{print $2}')"
    done
  done
done
unset RTCL_BUILD_OPTIONS
for s in tetra mount lake; do cmp -s $T/plain-$s.ppm $T/nolights-$s.ppm && echo "$s: images identical" || echo "$s: IMAGES DIFFER"; done
