"""Tests of tools/genscene.py and of every scene file in scenes/ (run with pytest)."""

import itertools
import math
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tools"))
from rtcl_tools import scene as scene_module  # noqa: E402
GENSCENE = os.path.join(ROOT, "tools", "genscene.py")
SCENES = os.path.join(ROOT, "scenes")


def genscene(*args):
    """Run the generator as the command line does; return its stdout."""
    done = subprocess.run([sys.executable, GENSCENE, *args], capture_output=True,
                          text=True, check=True)
    return done.stdout


# --- the scene validator shared with the tools (rtcl_tools.scene, mirroring host/scene/scene.c)

Invalid = scene_module.SceneError
load = scene_module.parse
validate = scene_module.validate


def test_validator_catches_mistakes():
    good = load(genscene("--balls", "3"))
    validate(good)
    bad_cases = [
        lambda s: s["spheres"][0].update(radus=1),
        lambda s: s["spheres"][0]["material"].update(reflect=1.5),
        lambda s: s["spheres"][0]["material"].update(color=[0.5, -0.1, 0.2]),
        lambda s: s["spheres"][0].update(material="nosuch"),
        lambda s: s.update(version=3),
        lambda s: s.update(triangles=[]),
        lambda s: s.update(colour=[0, 0, 0]),
        lambda s: s["planes"][0]["checker"].pop("size"),
    ]
    for spoil in bad_cases:
        scene = load(genscene("--balls", "3"))
        spoil(scene)
        with pytest.raises(Invalid):
            validate(scene)
    with pytest.raises(Invalid):
        load('{"format": "rtcl-scene", "format": "rtcl-scene"}')


# --- the generator ----------------------------------------------------------------

@pytest.fixture(scope="module")
def default_text():
    return genscene()


def test_same_seed_same_bytes(default_text):
    assert genscene() == default_text
    assert genscene("--seed", "5") == genscene("--seed", "5")


def test_other_seed_differs(default_text):
    assert genscene("--seed", "2010") != default_text
    a = load(genscene("--seed", "1"))["spheres"]
    b = load(genscene("--seed", "2"))["spheres"]
    assert [s["center"] for s in a] != [s["center"] for s in b]


def test_output_file_equals_stdout(tmp_path, default_text):
    out = tmp_path / "scene.json"
    assert genscene("-o", str(out)) == ""
    assert out.read_text() == default_text


def test_committed_paper60_is_the_default_output(default_text):
    with open(os.path.join(SCENES, "paper60.json"), encoding="utf-8") as f:
        assert f.read() == default_text, \
            "scenes/paper60.json drifted; regenerate with tools/genscene.py -o scenes/paper60.json"


def test_one_sphere_per_line(default_text):
    lines = [l for l in default_text.splitlines() if '"center"' in l]
    assert len(lines) == 60


@pytest.mark.parametrize("n", [0, 1, 7, 60, 600])
def test_ball_count_and_validity(n):
    scene = load(genscene("--balls", str(n)))
    validate(scene)
    assert len(scene["spheres"]) == n
    assert len(scene["lights"]) == 2


def placed_scenes():
    yield load(genscene())
    yield load(genscene("--seed", "7"))
    yield load(genscene("--balls", "600", "--seed", "3"))


def test_balls_rest_on_table_without_overlap():
    for scene in placed_scenes():
        (table,) = scene["planes"]
        assert table["point"] == [0, 0, 0] and table["normal"] == [0, 1, 0]
        assert table["checker"]["size"] > 0
        spheres = scene["spheres"]
        for s in spheres:
            assert s["center"][1] == s["radius"], s
        for a, b in itertools.combinations(spheres, 2):
            gap = math.dist(a["center"], b["center"]) - a["radius"] - b["radius"]
            assert gap > 0, (a, b)


def screen_disc(scene, center, radius):
    """Centre (x, y in [-1, 1]) and radius on screen, per RENDERING.md's camera."""
    cam = scene["camera"]
    eye, look = cam["eye"], cam["look_at"]
    f = [l - e for l, e in zip(look, eye)]
    n = math.sqrt(sum(c * c for c in f))
    f = [c / n for c in f]
    up = cam.get("up", [0, 1, 0])
    r = [f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]]
    n = math.sqrt(sum(c * c for c in r))
    r = [c / n for c in r]
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    h = math.tan(math.radians(cam.get("fov", 45)) / 2)
    v = [c - e for c, e in zip(center, eye)]
    depth = sum(a * b for a, b in zip(v, f))
    x = sum(a * b for a, b in zip(v, r)) / (depth * h)
    y = sum(a * b for a, b in zip(v, u)) / (depth * h)
    return x, y, radius / (depth * h)


def test_every_ball_is_in_the_picture_and_not_hidden():
    for scene in placed_scenes():
        discs = []
        for s in scene["spheres"]:
            x, y, rad = screen_disc(scene, s["center"], s["radius"])
            assert abs(x) + rad < 1 and abs(y) + rad < 1, s
            depth = math.dist(s["center"], scene["camera"]["eye"])
            discs.append((depth, x, y, rad))
        # No ball's screen centre is covered by a ball in front of it.
        for a, b in itertools.combinations(discs, 2):
            near, far = (a, b) if a[0] < b[0] else (b, a)
            assert math.hypot(near[1] - far[1], near[2] - far[2]) > near[3], (near, far)


def kind(material):
    if material.get("transmit", 0) > 0:
        return "glass"
    if material.get("reflect", 0) > 0:
        return "mirror"
    return "diffuse"


def test_material_mix():
    scene = load(genscene())
    kinds = [kind(s["material"]) for s in scene["spheres"]]
    assert (kinds.count("diffuse"), kinds.count("mirror"), kinds.count("glass")) == (36, 15, 9)
    for s in scene["spheres"]:
        m = s["material"]
        if kind(m) == "glass":
            assert m["ior"] == 1.5 and m["transmit"] >= 0.8 and m["reflect"] <= 0.2
        if kind(m) == "mirror":
            assert 0.6 <= m["reflect"] <= 0.8
    colors = {tuple(s["material"]["color"]) for s in scene["spheres"]}
    assert len(colors) == 60, "colours are random per ball"


def test_size_and_depth_options():
    scene = load(genscene("--size", "640x480", "--depth", "3"))
    assert scene["image"] == {"width": 640, "height": 480}
    assert scene["max_depth"] == 3
    default = load(genscene())
    assert default["image"] == {"width": 2000, "height": 2000}
    assert default["max_depth"] == 5 and default["epsilon"] == 1e-4
    assert scene["spheres"] == default["spheres"], "the layout does not depend on --size"


@pytest.mark.parametrize("args", [["--balls", "-1"], ["--size", "20x"], ["--size", "0x10"],
                                  ["--depth", "65"], ["--seed", "x"]])
def test_bad_options_are_refused(args):
    done = subprocess.run([sys.executable, GENSCENE, *args], capture_output=True, text=True)
    assert done.returncode == 2 and done.stdout == ""
    assert "error" in done.stderr


# --- the committed scenes -----------------------------------------------------------

SCENE_FILES = sorted(f for f in os.listdir(SCENES) if f.endswith(".json"))
TEST_SCENES = os.path.join(ROOT, "test", "scenes")


def test_expected_scenes_exist():
    for name in ("paper60.json", "two_balls.json", "tir.json", "empty.json"):
        assert name in SCENE_FILES


@pytest.mark.parametrize("path", [os.path.join(SCENES, name) for name in SCENE_FILES]
                         + [os.path.join(TEST_SCENES, name)
                            for name in sorted(os.listdir(TEST_SCENES))])
def test_scene_file_is_valid(path):
    with open(path, encoding="utf-8") as f:
        scene = load(f.read())
    validate(scene)


def test_scene_files_are_listed_in_readme():
    with open(os.path.join(SCENES, "README.md"), encoding="utf-8") as f:
        readme = f.read()
    for name in SCENE_FILES:
        assert name in readme


def test_special_scenes():
    def read(name):
        with open(os.path.join(SCENES, name), encoding="utf-8") as f:
            return load(f.read())
    empty = read("empty.json")
    assert not empty.get("spheres") and not empty.get("planes") and not empty.get("lights")
    assert any(empty["background"]) and empty["image"] == {"width": 320, "height": 240}
    two = read("two_balls.json")
    assert len(two["spheres"]) == 2 and two["image"] == {"width": 800, "height": 600}
    for s in two["spheres"]:
        m = two["materials"][s["material"]]
        assert m["reflect"] > 0 and m["transmit"] > 0
    a, b = two["spheres"]
    assert math.dist(a["center"], b["center"]) - a["radius"] - b["radius"] < 0.5

    tir = read("tir.json")
    assert tir["image"] == {"width": 640, "height": 480}
    # A ray entering a lone sphere meets its far side at the angle it was refracted
    # to, below the critical one: total internal reflection needs a surface inside
    # the glass, here air bubbles (ior 1/2.4) within a diamond ball (ior 2.4).
    mats = tir["materials"]
    for outer, inner in itertools.permutations(tir["spheres"], 2):
        mo, mi = mats[outer["material"]], mats[inner["material"]]
        if (mo["transmit"] > 0 and mi["transmit"] > 0 and mo["ior"] * mi["ior"] < 1.01
                and math.dist(outer["center"], inner["center"]) + inner["radius"]
                < outer["radius"]):
            break
    else:
        pytest.fail("tir.json has no bubble inside a glass ball")
