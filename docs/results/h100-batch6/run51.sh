#!/bin/bash
# GPU batch 51 (issue 26 item 3): Whitted and primary-ray scenes after
# RTCL_LEAF_TRIANGLES_ONLY (08bb2ae, .gpu/rtcl) against 3cc00d3's code
# (.gpu/rtcl-x, batch 49's binary with its switches off, and its own mesh
# helper .gpu/rtcl-meshread-x: the pipe protocol changed since). Persistent
# -w 8x8, 2000x2000, three interleaved rounds of -r 20, median kernel ms;
# images compared; then the rays each traces (counting run).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
T=$(mktemp -d)
python3 tools/genbench.py lake -o $T/lake > /dev/null
python3 - $T <<'PY'
import json, pathlib, sys
T = pathlib.Path(sys.argv[1])
scene = json.loads((T / "lake" / "lake-10.json").read_text())
mesh = dict(scene["meshes"][0]); mesh["file"] = str((T / "lake" / mesh["file"]).resolve())
primary = {"format": "rtcl-scene", "version": 2, "camera": scene["camera"],
           "materials": scene.get("materials", {}), "image": {"width": 2000, "height": 2000},
           "background": [1, 0, 1], "max_depth": 0, "lights": [], "meshes": [mesh]}
(T / "lake-primary.json").write_text(json.dumps(primary))
PY
declare -A S=([lake-primary]="-s $T/lake-primary.json" [lake]="-s $T/lake/lake-10.json --size 2000x2000"
  [glass_mesh]="-s scenes/glass_mesh.json --size 2000x2000" [paper60]="--size 2000x2000")
SCENES="paper60 lake-primary lake glass_mesh"
for round in 1 2 3; do
  for s in $SCENES; do
    for b in rtcl-x rtcl; do
      [ $b = rtcl-x ] && export RTCL_MESHREAD=$G/rtcl-meshread-x || export RTCL_MESHREAD=$G/rtcl-meshread
      $G/$b -p $P -k persistent -w 8x8 ${S[$s]} -r 20 -q -o $T/$b-$s.ppm --stats $T/s.json
      echo "round $round $s $b kernel_ms $(grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1 | awk '{print $2}')"
    done
  done
done
for s in $SCENES; do
  python3 -c "import sys; n=2000*2000*3; a=open(sys.argv[1],'rb').read()[-n:]; b=open(sys.argv[2],'rb').read()[-n:]; print('  $s:', 'pixels identical' if a == b else 'PIXELS DIFFER: %d bytes' % sum(x != y for x, y in zip(a, b)))" $T/rtcl-x-$s.ppm $T/rtcl-$s.ppm
done
for s in $SCENES; do
  $G/rtcl -p $P -k persistent -w 8x8 ${S[$s]} -q -o $T/c.ppm --flops $T/f.npy --stats $T/c.json
  echo "counted $s rays $(grep -o '"rays": [0-9]*' $T/c.json | head -1 | awk '{print $2}') leaf_triangles_only $(grep -c LEAF_TRIANGLES_ONLY $T/c.json)"
done
