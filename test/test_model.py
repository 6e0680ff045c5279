"""A model file rendered alone (issue 44, item 1; docs/SCENE.md, "A model file
alone"): `rtcl MODEL` renders an OBJ, PLY, STL or glTF file with its own
materials, textures and camera; without a camera, a view framed from its bounds
by a documented rule; without a light, the default stage. `-s MODEL` says it is
a model and how to render it; glTF 1.0 is refused with how to convert it."""
import json
import math
import os
import pathlib
import re
import struct
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
MODELS = ROOT / "scenes" / "models"
MESHES = ROOT / "test" / "meshes"


def rtcl(*args, cwd):
    return subprocess.run([RTCL, *args], cwd=cwd, capture_output=True, text=True, timeout=300)


def read_ppm(path):
    """(width, height), RGB bytes of a binary PPM with comments."""
    data = path.read_bytes()
    assert data.startswith(b"P6\n")
    fields, i = [], 3
    while len(fields) < 3:
        if data[i:i + 1] == b"#":
            i = data.index(b"\n", i) + 1
            continue
        j = i
        while data[j:j + 1] not in b" \n":
            j += 1
        fields.append(int(data[i:j]))
        i = j + 1
    width, height, _ = fields
    return (width, height), data[i:]


def vec(text):
    return [float(v) for v in text.split(", ")]


def framed_view(stderr):
    """eye, look_at, fov of -v's line on a framed view."""
    m = re.search(r"the view framed from its bounds, eye \[([^]]*)\], look_at \[([^]]*)\], "
                  r"fov (\S+)", stderr)
    assert m, stderr
    return vec(m[1]), vec(m[2]), float(m[3])


# make test renders an OBJ and a PLY here and glTF files below; make test-long
# the rest (each model's program is a build of its own on a cold cache).
@pytest.mark.parametrize("model", [MODELS / "crate.obj", MESHES / "quad.ply",
                                   pytest.param(MODELS / "trellis.gltf", marks=pytest.mark.slow),
                                   pytest.param(MESHES / "tri.stl", marks=pytest.mark.slow)])
def test_a_model_file_renders_alone_with_the_default_stage(tmp_path, model):
    result = rtcl(str(model), "-v", "--size", "40x30", "--spp", "1", "-o", "m.ppm",
                  cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "no camera of its own: the view framed from its bounds" in result.stderr
    assert "no light of its own: the default stage" in result.stderr
    assert f"scene {model}" in result.stdout
    size, pixels = read_ppm(tmp_path / "m.ppm")
    assert size == (40, 30)
    assert len(set(pixels)) > 10  # lit and shaded, not one flat colour


def test_the_model_keeps_its_own_texture_and_fills_the_centre(tmp_path):
    # The crate's texture is brown wood: the centre of the framed view is
    # the crate (the view looks at its centre), in its texture's colours.
    result = rtcl(str(MODELS / "crate.obj"), "--size", "32x24", "--spp", "1", "-o", "m.ppm",
                  cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    (width, height), pixels = read_ppm(tmp_path / "m.ppm")
    centre = 3 * (height // 2 * width + width // 2)
    r, g, b = pixels[centre:centre + 3]
    assert r > g > b and r - b > 40, (r, g, b)


def corners(lo, hi):
    return [[(lo, hi)[(k >> i) & 1][i] for i in range(3)] for k in range(8)]


@pytest.mark.parametrize("size", ["64x48", pytest.param("30x90", marks=pytest.mark.slow),
                                  pytest.param("200x20", marks=pytest.mark.slow)])
def test_the_framed_view_holds_the_whole_model_from_a_three_quarter_view(tmp_path, size):
    result = rtcl(str(MODELS / "crate.obj"), "-v", "--size", size, "--spp", "1", "-o", "m.ppm",
                  cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    eye, look_at, fov = framed_view(result.stderr)
    lo, hi = [-0.5] * 3, [0.5] * 3  # the crate's box
    assert look_at == pytest.approx([0, 0, 0])
    # 45 degrees right of the front (+z), 30 degrees up.
    d = [e - c for e, c in zip(eye, look_at)]
    length = math.sqrt(sum(v * v for v in d))
    assert math.degrees(math.asin(d[1] / length)) == pytest.approx(30, abs=0.01)
    assert math.degrees(math.atan2(d[0], d[2])) == pytest.approx(45, abs=0.01)
    # Every corner of the box projects inside the image.
    width, height = (int(v) for v in size.split("x"))
    f = [-v / length for v in d]
    right = [f[1] * 0 - f[2] * 1, f[2] * 0 - f[0] * 0, f[0] * 1 - f[1] * 0]
    rl = math.sqrt(sum(v * v for v in right))
    right = [v / rl for v in right]
    up = [right[1] * f[2] - right[2] * f[1], right[2] * f[0] - right[0] * f[2],
          right[0] * f[1] - right[1] * f[0]]
    tan_v = math.tan(math.radians(fov) / 2)
    tan_h = tan_v * width / height
    worst = 0
    for p in corners(lo, hi):
        q = [a - e for a, e in zip(p, eye)]
        z = sum(a * b for a, b in zip(q, f))
        x = sum(a * b for a, b in zip(q, right)) / z / tan_h
        y = sum(a * b for a, b in zip(q, up)) / z / tan_v
        worst = max(worst, abs(x), abs(y))
    assert 0.5 < worst < 1, worst  # in view, and not lost in the middle


def test_a_model_with_a_camera_is_seen_through_it(tmp_path):
    result = rtcl(str(MESHES / "camera.gltf"), "-v", "--size", "24x18", "--spp", "1", "-o",
                  "m.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert 'camera "Cam": eye [0.5, 0, -4]' in result.stderr
    assert "framed" not in result.stderr


@pytest.mark.slow
def test_image_options_apply_to_a_model_as_to_a_scene(tmp_path):
    result = rtcl(str(MODELS / "cube.obj"), "--size", "16x12", "--eye", "3,2,4", "--frames",
                  "0:1", "-k", "naive", "-o", "f.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(tmp_path)) == ["f_0000.ppm", "f_0001.ppm"]
    result = rtcl(str(MODELS / "cube.obj"), "--size", "16x12", "-o", "m.ppm", cwd=tmp_path)
    assert "samples: 4 per pixel" in result.stdout  # a model's default


def test_a_model_given_as_a_scene_says_how_to_render_it(tmp_path):
    for model, before in [(MODELS / "cube.obj", "'[' or '{' expected"),
                          (MODELS / "trellis.gltf", "format: required field is missing")]:
        result = rtcl("-s", str(model), "-o", "m.png", cwd=tmp_path)
        assert result.returncode == 1
        assert before in result.stderr
        assert (f'{model} is a model file, not an rtcl scene: render it alone with '
                f'"rtcl {model}"') in result.stderr
    assert os.listdir(tmp_path) == []


def test_the_model_file_is_an_input_no_output_may_replace(tmp_path):
    (tmp_path / "cube.obj").write_bytes((MODELS / "cube.obj").read_bytes())
    result = rtcl("cube.obj", "--stats", "cube.obj", "-o", "m.png", cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert "rtcl does not replace a file the run reads" in result.stderr


def test_a_model_that_is_not_one_is_refused_with_the_importers_reason(tmp_path):
    result = rtcl(str(MESHES / "garbage.obj"), "-o", "m.png", cwd=tmp_path)
    assert result.returncode == 1
    assert result.stderr.count("\n") == 1 and "meshes[0]" not in result.stderr
    assert os.listdir(tmp_path) == []


def test_gltf_1_files_are_refused_with_how_to_convert_them(tmp_path):
    (tmp_path / "old.gltf").write_text(json.dumps(
        {"asset": {"version": "1.0"}, "scene": "s", "scenes": {"s": {"nodes": []}}}))
    (tmp_path / "old.glb").write_bytes(b"glTF" + struct.pack("<II", 1, 20) + bytes(8))
    scene = {"format": "rtcl-scene", "version": 2, "camera": {"eye": [0, 0, 5],
             "look_at": [0, 0, 0]}, "meshes": [{"file": "old.gltf"}]}
    (tmp_path / "s.json").write_text(json.dumps(scene))
    for args in (["old.gltf"], ["old.glb"], ["s.json"]):
        result = rtcl(*args, "-o", "m.png", cwd=tmp_path)
        assert result.returncode == 1, result.stderr
        assert "is a glTF 1.0 file, whose materials rtcl cannot read: convert it to glTF " \
               "2.0 (e.g. \"npx gltf-pipeline -i old.gl" in result.stderr
    assert "m.png" not in os.listdir(tmp_path)


def lit_gltf(path):
    """camera.gltf's quad and triangle with KHR_lights_punctual lights instead
    of cameras: a red point light, a green sun down -z, a blue spot light."""
    doc = json.loads((MESHES / "camera.gltf").read_text())
    doc["scenes"][0]["nodes"] = [0, 1, 2, 3]
    light = lambda i: {"KHR_lights_punctual": {"light": i}}  # noqa: E731
    doc["nodes"] = [{"mesh": 0},
                    {"name": "Lamp", "translation": [0, 0, 3], "extensions": light(0)},
                    {"name": "Sun", "extensions": light(1)},
                    {"name": "Spot", "translation": [0, 0, 5], "extensions": light(2)}]
    del doc["cameras"]
    doc["extensionsUsed"] = ["KHR_lights_punctual"]
    doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 0, 0], "intensity": 10},
        {"type": "directional", "color": [0, 1, 0], "intensity": 1},
        {"type": "spot", "color": [0, 0, 1], "intensity": 10, "spot": {"outerConeAngle": 0.5}}]}}
    path.write_text(json.dumps(doc))


def test_a_model_with_lights_is_lit_by_them_and_gets_no_stage(tmp_path):
    lit_gltf(tmp_path / "lit.gltf")
    result = rtcl("lit.gltf", "-v", "--size", "32x24", "--spp", "1", "-o", "m.ppm",
                  cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "model lit.gltf: 3 lights of its own, scaled together" in result.stderr
    assert 'light "Spot": a spot light, lit as a point light' in result.stderr
    assert "default stage" not in result.stderr
    # The quad (default material, facing +z) at the centre: lit red most
    # (the lamp: 10 / 2.75^2 = 1.32, scaled to 1), green (the sun: 1 / 1.32)
    # and blue least (the spot: 10 / 4.75^2 = 0.44, / 1.32).
    (width, height), pixels = read_ppm(tmp_path / "m.ppm")
    centre = 3 * (height // 2 * width + width // 2)
    r, g, b = pixels[centre:centre + 3]
    assert r > g > b, (r, g, b)
