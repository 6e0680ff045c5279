#!/bin/bash
# GPU batch 86 (issue 26, H100): an experiment on the peer comparison's
# primary rays (max_depth 0, no lights, the mesh alone): a triangle hit's
# geometric normal (its index, then three vertices read again) is used by
# nothing there; RTCL_X_SKIP_NORMAL (run86-experiment.patch on 7bc52c9,
# .gpu/rtcl-x) skips it. Persistent and naive, -r 10, three interleaved
# rounds, median kernel ms; pixels compared.
#   COMMIT=<commit> bash docs/results/h100-batch9/run86.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
echo "commit: $COMMIT"; nvidia-smi -L
G=$PWD/.gpu; X=$G/rtcl-x; T=$(mktemp -d)
P=$($X --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py tetra --size 8 --triangles ply -o $T/tetra > /dev/null
python3 tools/genbench.py mount --size 8 --triangles ply -o $T/mount > /dev/null
python3 tools/genbench.py lake -o $T/lake > /dev/null
python3 - $T <<'PY'
import json, pathlib, sys
T = pathlib.Path(sys.argv[1])
for name, folder in (("tetra-8", "tetra"), ("mount-8", "mount"), ("lake-10", "lake")):
    (src,) = (T / folder).glob("*.json")
    scene = json.loads(src.read_text())
    mesh = dict(scene["meshes"][0]); mesh["file"] = str((src.parent / mesh["file"]).resolve())
    kept = {k: scene[k] for k in ("format", "camera", "materials") if k in scene}
    (T / f"{name}-primary.json").write_text(json.dumps({**kept, "version": 2,
        "image": {"width": 2000, "height": 2000}, "background": [1, 0, 1], "max_depth": 0,
        "lights": [], "meshes": [mesh]}))
PY
for round in 1 2 3; do
  for m in tetra-8 mount-8 lake-10; do
    for k in naive persistent; do
      for v in "" -DRTCL_X_SKIP_NORMAL; do
        RTCL_BUILD_OPTIONS=$v $X -p $P -k $k -r 10 -s $T/$m-primary.json -q -o $T/$m-$k${v:+-x}.ppm --stats $T/s.json
        echo "round $round $m $k ${v:-as-main} kernel_ms $(python3 -c "import json; print(json.load(open('$T/s.json'))['kernel_ms'])")"
      done
      [ $round = 1 ] && python3 tools/ppmdiff.py $T/$m-$k.ppm $T/$m-$k-x.ppm | tail -1
    done
  done
done
