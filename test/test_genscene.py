"""Tests of tools/genscene.py and of every scene file in scenes/ (run with pytest)."""

import itertools
import json
import math
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GENSCENE = os.path.join(ROOT, "tools", "genscene.py")
SCENES = os.path.join(ROOT, "scenes")


def genscene(*args):
    """Run the generator as the command line does; return its stdout."""
    done = subprocess.run([sys.executable, GENSCENE, *args], capture_output=True,
                          text=True, check=True)
    return done.stdout


# --- a validator written from SCENE.md, independent of the generator -------------

TOP_KEYS = {"format", "version", "image", "camera", "background", "ambient",
            "max_depth", "epsilon", "materials", "lights", "spheres", "planes"}
MATERIAL_KEYS = {"color", "ambient", "diffuse", "specular", "shininess", "reflect",
                 "transmit", "ior"}


class Invalid(Exception):
    pass


def expect(ok, path, what):
    if not ok:
        raise Invalid("%s: %s" % (path, what))


def no_duplicate_keys(pairs):
    keys = [k for k, _ in pairs]
    dup = {k for k in keys if keys.count(k) > 1}
    if dup:
        raise Invalid("duplicate key(s) %s" % sorted(dup))
    return dict(pairs)


def load(text):
    return json.loads(text, object_pairs_hook=no_duplicate_keys)


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def is_integer(v):
    return isinstance(v, int) and not isinstance(v, bool)


def check_keys(obj, allowed, path, required=()):
    expect(isinstance(obj, dict), path, "must be an object")
    for key in obj:
        expect(key in allowed, path, "unknown key %r" % key)
    for key in required:
        expect(key in obj, path, "missing %r" % key)


def check_vec3(v, path):
    expect(isinstance(v, list) and len(v) == 3 and all(map(is_number, v)), path,
           "must be an array of three finite numbers, got %r" % (v,))


def check_color(v, path):
    check_vec3(v, path)
    expect(all(c >= 0 for c in v), path, "colour parts must be >= 0, got %r" % (v,))


def check_material(m, path):
    check_keys(m, MATERIAL_KEYS, path)
    if "color" in m:
        check_color(m["color"], path + ".color")
    for key in ("ambient", "diffuse", "specular", "shininess", "reflect", "transmit", "ior"):
        if key in m:
            expect(is_number(m[key]), path + "." + key, "must be a number")
            # SCENE.md states no range for ka, kd, ks; negative ones would be nonsense.
            expect(m[key] >= 0, path + "." + key, "must be >= 0, got %r" % m[key])
    for key in ("reflect", "transmit"):
        if key in m:
            expect(m[key] <= 1, path + "." + key, "must be <= 1, got %r" % m[key])
    if "ior" in m:
        expect(m["ior"] > 0, path + ".ior", "must be > 0")


def check_material_ref(m, materials, path):
    if isinstance(m, str):
        expect(m in materials, path, "unknown material %r" % m)
    else:
        check_material(m, path)


def validate(scene):
    """Raise Invalid unless scene (a parsed document) follows SCENE.md."""
    check_keys(scene, TOP_KEYS, "scene", required=("format", "version", "camera"))
    expect(scene["format"] == "rtcl-scene", "format", "must be \"rtcl-scene\"")
    expect(is_integer(scene["version"]) and scene["version"] == 1, "version", "must be 1")

    image = scene.get("image", {})
    check_keys(image, {"width", "height"}, "image")
    for key in ("width", "height"):
        if key in image:
            expect(is_integer(image[key]) and 1 <= image[key] <= 32768, "image." + key,
                   "must be an integer 1 ... 32768")

    cam = scene["camera"]
    check_keys(cam, {"eye", "look_at", "up", "fov"}, "camera", required=("eye", "look_at"))
    check_vec3(cam["eye"], "camera.eye")
    check_vec3(cam["look_at"], "camera.look_at")
    forward = [a - b for a, b in zip(cam["look_at"], cam["eye"])]
    expect(any(forward), "camera", "eye and look_at must differ")
    up = cam.get("up", [0, 1, 0])
    check_vec3(up, "camera.up")
    cross = [forward[1] * up[2] - forward[2] * up[1], forward[2] * up[0] - forward[0] * up[2],
             forward[0] * up[1] - forward[1] * up[0]]
    expect(math.sqrt(sum(c * c for c in cross)) > 1e-9, "camera.up", "parallel to the view")
    fov = cam.get("fov", 45)
    expect(is_number(fov) and 0 < fov < 180, "camera.fov", "must be in (0, 180)")

    for key in ("background", "ambient"):
        if key in scene:
            check_color(scene[key], key)
    if "max_depth" in scene:
        expect(is_integer(scene["max_depth"]) and 0 <= scene["max_depth"] <= 64,
               "max_depth", "must be an integer 0 ... 64")
    if "epsilon" in scene:
        expect(is_number(scene["epsilon"]) and scene["epsilon"] > 0, "epsilon", "must be > 0")

    materials = scene.get("materials", {})
    expect(isinstance(materials, dict), "materials", "must be an object")
    for name, m in materials.items():
        check_material(m, "materials." + name)

    for key in ("lights", "spheres", "planes"):
        expect(isinstance(scene.get(key, []), list), key, "must be an array")
    for i, light in enumerate(scene.get("lights", [])):
        path = "lights[%d]" % i
        check_keys(light, {"position", "color"}, path, required=("position",))
        check_vec3(light["position"], path + ".position")
        if "color" in light:
            check_color(light["color"], path + ".color")
    for i, s in enumerate(scene.get("spheres", [])):
        path = "spheres[%d]" % i
        check_keys(s, {"center", "radius", "material"}, path, required=("center", "radius"))
        check_vec3(s["center"], path + ".center")
        expect(is_number(s["radius"]) and s["radius"] > 0, path + ".radius", "must be > 0")
        if "material" in s:
            check_material_ref(s["material"], materials, path + ".material")
    for i, p in enumerate(scene.get("planes", [])):
        path = "planes[%d]" % i
        check_keys(p, {"point", "normal", "material", "checker"}, path,
                   required=("point", "normal"))
        check_vec3(p["point"], path + ".point")
        check_vec3(p["normal"], path + ".normal")
        expect(any(p["normal"]), path + ".normal", "must be non-zero")
        if "material" in p:
            check_material_ref(p["material"], materials, path + ".material")
        if "checker" in p:
            c = p["checker"]
            check_keys(c, {"size", "color"}, path + ".checker", required=("size", "color"))
            expect(is_number(c["size"]) and c["size"] > 0, path + ".checker.size", "must be > 0")
            check_color(c["color"], path + ".checker.color")


def test_validator_catches_mistakes():
    good = load(genscene("--balls", "3"))
    validate(good)
    bad_cases = [
        lambda s: s["spheres"][0].update(radus=1),
        lambda s: s["spheres"][0]["material"].update(reflect=1.5),
        lambda s: s["spheres"][0]["material"].update(color=[0.5, -0.1, 0.2]),
        lambda s: s["spheres"][0].update(material="nosuch"),
        lambda s: s.update(version=2),
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


def test_expected_scenes_exist():
    for name in ("paper60.json", "two_balls.json", "tir.json", "empty.json"):
        assert name in SCENE_FILES


@pytest.mark.parametrize("name", SCENE_FILES)
def test_scene_file_is_valid(name):
    with open(os.path.join(SCENES, name), encoding="utf-8") as f:
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
