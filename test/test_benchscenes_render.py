"""Every kind of version 2 benchmark scene that tools/genbench.py writes renders
through ./rtcl, and its triangles show: tetra and mount inline and as binary PLY
(uchar-int face lists read through assimp), the lake (at a small size: the full
lake-10 takes minutes by brute force) and the assimp-testmodels scene with its
absolute paths.  The version 1 ones (balls, random balls) render in test_spd.py."""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import benchscenes  # noqa: E402

RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
GENBENCH = ROOT / "tools" / "genbench.py"
WIDTH, HEIGHT = 32, 24

needs_models = pytest.mark.skipif(
    not os.path.isdir(benchscenes.ASSIMP_MODELS), reason="assimp-testmodels not installed")


def render(scene_path, out):
    """Returns the pixels (H x W x 3, 8-bit) of scene_path rendered at WIDTH x HEIGHT."""
    done = subprocess.run([RTCL, "-s", str(scene_path), "--size", f"{WIDTH}x{HEIGHT}",
                           "-o", str(out)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    data = out.read_bytes()
    assert data.startswith(b"P6")
    return np.frombuffer(data[-WIDTH * HEIGHT * 3:], dtype=np.uint8).reshape(HEIGHT, WIDTH, 3)


def without(scene_path, keys, name):
    """Writes a copy of the scene beside it without the given top-level keys."""
    doc = json.loads(scene_path.read_text())
    for key in keys:
        doc.pop(key, None)
    copy = scene_path.with_name(name)
    copy.write_text(json.dumps(doc))
    return copy


@pytest.mark.parametrize("args, name, mesh_file", [
    (["tetra", "--size", "2"], "spd-tetra-2", False),
    (["tetra", "--size", "3", "--triangles", "ply"], "spd-tetra-3", True),
    (["mount", "--size", "2"], "spd-mount-2", False),
    (["mount", "--size", "3", "--triangles", "ply"], "spd-mount-3", True),
    (["lake", "--size", "3"], "lake-3", True),
    pytest.param(["assimp"], "assimp-models", False, marks=needs_models),
], ids=lambda value: value if isinstance(value, str) else None)
def test_generated_scene_renders_and_its_triangles_show(tmp_path, args, name, mesh_file):
    subprocess.run([sys.executable, str(GENBENCH), *args, "-o", str(tmp_path)], check=True,
                   capture_output=True)
    scene_path = tmp_path / f"{name}.json"
    doc = json.loads(scene_path.read_text())
    assert doc["version"] == 2
    if mesh_file:
        assert (tmp_path / doc["meshes"][0]["file"]).suffix == ".ply"
    image = render(scene_path, tmp_path / "full.ppm")
    empty = render(without(scene_path, ("spheres", "planes", "meshes", "triangles"),
                           "empty.json"), tmp_path / "empty.ppm")
    no_triangles = render(without(scene_path, ("meshes", "triangles"), "flat.json"),
                          tmp_path / "flat.ppm")
    # Not all background, and the triangles cover a good part of the picture.
    assert np.any(image != empty, axis=2).mean() > 0.05
    assert np.any(image != no_triangles, axis=2).mean() > 0.05
