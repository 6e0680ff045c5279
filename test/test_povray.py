"""Tests of tools/povray.py (the POV-Ray 3.7 baseline of issue 4).

The SDL is checked against the scene and docs/RENDERING.md, independently of the
tool's own arithmetic: spheres (mirrored in x), lights, global settings, the
camera (POV-Ray's primary ray for a pixel, worked out from the SDL, must be
RENDERING.md's), the checker (POV-Ray's 3D checker evaluated through the SDL's
pattern transform must give floor(s/size) + floor(t/size) parity), the material
compensation and the shadow clones.  Errors: one line on stderr, no file.  When
povray is installed, small renders are compared with ./rtcl (or $RTCL) pixel by
pixel: this is what shows the camera and geometry mapping really match.
"""
import json
import math
import os
import pathlib
import random
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import ply, ppm  # noqa: E402
TOOL = ROOT / "tools" / "povray.py"
SCENES = ROOT / "scenes"
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
HAVE_POVRAY = shutil.which("povray") is not None

NUM = r"-?[0-9.]+(?:e[-+]?[0-9]+)?"
VEC = r"<\s*(%s),\s*(%s),\s*(%s)\s*>" % (NUM, NUM, NUM)


def run_tool(*args, cwd=None):
    return subprocess.run([sys.executable, str(TOOL), *map(str, args)], capture_output=True,
                          text=True, cwd=cwd or ROOT, timeout=600)


def sdl(*args):
    done = run_tool(*args)
    assert done.returncode == 0, done.stderr
    return done.stdout


def vector(text):
    return tuple(float(x) for x in re.fullmatch(VEC, text.strip()).groups())


def one_vector(text, keyword):
    m = re.search(r"\b%s\s+(%s)" % (keyword, VEC), text)
    assert m, keyword
    return vector(m.group(1))


def scene_json(name):
    return json.loads((SCENES / name).read_text())


def assert_one_line_error(result, *fragments):
    assert result.returncode == 1, (result.returncode, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("povray.py: ")
    for fragment in fragments:
        assert fragment in lines[0]


# ---- the SDL ------------------------------------------------------------------------

def visible_spheres(text):
    """[(center, radius, following text)] of every sphere that is not a shadow clone."""
    found = []
    for m in re.finditer(r"^sphere \{ (%s), (%s)(.*)$" % (VEC, NUM), text, re.M):
        if "no_image" not in m.group(6):
            found.append((vector(m.group(1)), float(m.group(5))))
    return found


def test_one_sphere_per_scene_sphere_mirrored_in_x():
    scene = scene_json("paper60.json")
    spheres = visible_spheres(sdl())
    assert len(spheres) == len(scene["spheres"]) == 60
    for (center, radius), s in zip(spheres, scene["spheres"]):
        x, y, z = s["center"]
        assert center == pytest.approx((-x, y, z), abs=1e-12)
        assert radius == pytest.approx(s["radius"], abs=1e-12)


def test_lights_mirrored_with_their_colours():
    scene = scene_json("two_balls.json")
    text = sdl("-s", "scenes/two_balls.json")
    lights = re.findall(r"light_source \{ (%s) color rgb (%s) \}" % (VEC, VEC), text)
    assert len(lights) == 2
    for found, light in zip(lights, scene["lights"]):
        x, y, z = light["position"]
        assert vector(found[0]) == pytest.approx((-x, y, z))
        assert vector(found[4]) == pytest.approx(tuple(light["color"]))


@pytest.mark.parametrize("args, level", [((), 6), (("--depth", "0"), 1),
                                         (("--depth", "3"), 4), (("--depth", "64"), 65)])
def test_global_settings(args, level):
    text = sdl(*args)
    assert text.count("#version 3.7;") == 1
    assert re.search(r"^\s*max_trace_level %d$" % level, text, re.M)
    assert re.search(r"^\s*adc_bailout 0$", text, re.M)
    assert re.search(r"^\s*assumed_gamma 1\.0$", text, re.M)
    assert one_vector(text, "ambient_light rgb") == pytest.approx((0.1, 0.1, 0.1))
    assert one_vector(text, "background { color rgb") == pytest.approx((0.12, 0.16, 0.24))


def rendering_md_ray(camera, width, height, x, y):
    """The primary ray direction of RENDERING.md, in rtcl's world."""
    eye, look, up = (np.array(camera[k], float) for k in ("eye", "look_at", "up"))
    f = (look - eye) / np.linalg.norm(look - eye)
    r = np.cross(f, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    h = math.tan(math.radians(camera["fov"]) / 2)
    a = width / height
    d = f + ((2 * (x + 0.5) / width - 1) * a * h) * r + ((1 - 2 * (y + 0.5) / height) * h) * u
    return d / np.linalg.norm(d)


@pytest.mark.parametrize("name, size", [("paper60.json", (2000, 2000)),
                                        ("two_balls.json", (64, 48)),
                                        ("tir.json", (97, 301))])
def test_camera_gives_rendering_md_rays(name, size):
    """POV-Ray 3.7's perspective ray for pixel (x, y) is direction
    + ((x+0.5)/W - 0.5) right + (0.5 - (y+0.5)/H) up (tracepixel.cpp)."""
    w, h = size
    text = sdl("-s", SCENES / name, "--size", "%dx%d" % size)
    camera_block = re.search(r"camera \{(.*?)\}", text, re.S).group(1)
    assert "perspective" in camera_block and "look_at" not in camera_block
    assert "angle" not in camera_block
    loc, right, up, direction = (np.array(one_vector(camera_block, k))
                                 for k in ("location", "right", "up", "direction"))
    camera = scene_json(name)["camera"]
    camera.setdefault("up", [0, 1, 0])
    camera.setdefault("fov", 45)
    ex, ey, ez = camera["eye"]
    assert tuple(loc) == pytest.approx((-ex, ey, ez))
    for x, y in [(0, 0), (w - 1, 0), (0, h - 1), (w - 1, h - 1), (w // 2, h // 3)]:
        d = direction + ((x + 0.5) / w - 0.5) * right + (0.5 - (y + 0.5) / h) * up
        d = d / np.linalg.norm(d)
        d[0] = -d[0]                                   # back to rtcl's world
        assert d == pytest.approx(rendering_md_ray(camera, w, h, x, y), abs=1e-12)


def write_scene(tmp_path, **overrides):
    scene = {"format": "rtcl-scene", "version": 1, "image": {"width": 64, "height": 48},
             "camera": {"eye": [0, 3, -8], "look_at": [0, 0, 0]}}
    scene.update(overrides)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    return path


def pov_checker_parity(text, point):
    """Evaluate POV-Ray's checker pattern (pattern.cpp: parity of the sum of
    floor(c + 1e-10)) through the pigment's transforms, at an rtcl world point."""
    m = re.search(r"checker color rgbt (<[^>]*>), color rgbt (<[^>]*>)\s+scale (%s) "
                  r"translate (%s) scale <-1, 1, 1>" % (VEC, VEC), text)
    assert m, text
    scales = np.array(vector(m.group(3)))
    offsets = np.array(vector(m.group(7)))
    pov = np.array([-point[0], point[1], point[2]])       # POV-Ray's world
    q = (pov * np.array([-1, 1, 1]) - offsets) / scales  # inverse of the transforms
    return int(sum(math.floor(c + 1e-10) for c in q)) & 1


@pytest.mark.parametrize("normal", [[0, 1, 0], [0, 0, -1], [1, 0, 0], [0.3, -1, 0.2],
                                    [1, 1, 0.5], [0.2, 0.1, 0.9]])
def test_checker_matches_rendering_md(tmp_path, normal):
    origin = [0.3, -1.7, 2.9]
    size = 0.7
    path = write_scene(tmp_path, planes=[{"point": origin, "normal": normal,
                                          "checker": {"size": size, "color": [0, 0, 0]}}])
    text = sdl("-s", path)
    n = np.array(normal, float) / np.linalg.norm(normal)
    drop = int(np.argmax(np.abs(n)))
    keep = [i for i in range(3) if i != drop]
    rng = random.Random(4)
    a = np.cross(n, [1, 0, 0] if abs(n[0]) < 0.9 else [0, 1, 0])
    a /= np.linalg.norm(a)
    b = np.cross(n, a)
    for _ in range(500):
        p = np.array(origin) + rng.uniform(-40, 40) * a + rng.uniform(-40, 40) * b
        expected = int(sum(math.floor(p[i] / size) for i in keep)) & 1
        assert pov_checker_parity(text, p) == expected, p
    # the plane itself: normal mirrored, distance n.point
    m = re.search(r"^plane \{ (%s), (%s)$" % (VEC, NUM), text, re.M)
    assert vector(m.group(1)) == pytest.approx((-n[0], n[1], n[2]))
    assert float(m.group(5)) == pytest.approx(float(np.dot(n, origin)))


def test_checker_colours_in_order():
    text = sdl("-s", "scenes/two_balls.json")
    m = re.search(r"checker color rgbt (<[^>]*>), color rgbt (<[^>]*>)", text)
    assert m.group(1) == "<0.9, 0.9, 0.85, 0>" and m.group(2) == "<0.15, 0.15, 0.15, 0>"


def test_glass_material_compensates_opacity():
    """POV-Ray scales ambient and diffuse by 1 - transmit: the SDL divides them."""
    scene = scene_json("paper60.json")
    text = sdl()
    blocks = re.findall(r"^sphere \{ [^\n]*\n  texture \{ pigment \{ color rgbt (<[^>]*>) \}\n"
                        r"    finish \{ ([^\n]*) \} \}\n(  interior \{ ior (%s) \}\n)?\}" % NUM,
                        text, re.M)
    assert len(blocks) == 60
    for (rgbt, fin, _, ior), s in zip(blocks, scene["spheres"]):
        m = s["material"]
        kt = m.get("transmit", 0)
        c = [float(v) for v in rgbt.strip("<>").split(",")]
        assert c == pytest.approx(m["color"] + [kt])
        values = dict(re.findall(r"(ambient|diffuse|specular|roughness) (%s)" % NUM, fin))
        assert float(values["ambient"]) * (1 - kt) == pytest.approx(m.get("ambient", 1.0))
        assert float(values["diffuse"]) * (1 - kt) == pytest.approx(m.get("diffuse", 0.7))
        assert float(values["specular"]) == pytest.approx(m.get("specular", 0.3))
        assert 1 / float(values["roughness"]) == pytest.approx(m.get("shininess", 32))
        reflection = re.search(r"reflection \{ (%s) \}" % NUM, fin)
        assert (float(reflection.group(1)) if reflection else 0) == pytest.approx(m.get("reflect", 0))
        assert (float(ior) if ior else None) == (m["ior"] if kt > 0 else None)


def test_shadow_clones_one_per_transparent_object():
    scene = scene_json("paper60.json")
    glass = [s for s in scene["spheres"] if s["material"].get("transmit", 0) > 0]
    text = sdl()
    clones = re.findall(r"^sphere \{ (%s), (%s) pigment \{ rgb 0 \}.*no_image no_reflection"
                        % (VEC, NUM), text, re.M)
    assert len(clones) == len(glass) == 9
    for (center, _, _, _, radius), s in zip(clones, glass):
        x, y, z = s["center"]
        assert vector(center) == pytest.approx((-x, y, z))
        assert s["radius"] * (1 - 1e-5) < float(radius) < s["radius"]
    assert "no_image" not in sdl("--transparent-shadows")


def test_nested_transparent_sphere_gets_product_of_iors():
    text = sdl("-s", "scenes/tir.json")
    iors = [float(v) for v in re.findall(r"interior \{ ior (%s) \}" % NUM, text)]
    # diamond 2.4, three bubbles (0.4167) inside it, the glass ball 1.5 outside
    assert iors == pytest.approx([2.4, 2.4 * 0.4167, 2.4 * 0.4167, 2.4 * 0.4167, 1.5])


def uv_ball_scene(tmp_path, **mesh):
    """A version 2 scene: a UV sphere mesh (its seam's vertices duplicated, so
    smooth normals must be summed over equal positions), one inline triangle
    and one mesh triangle of area 0, which rtcl skips."""
    nu, nv = 12, 8
    theta = np.pi * np.arange(nv + 1) / nv
    phi = 2 * np.pi * np.arange(nu + 1) / nu
    t, p = np.meshgrid(theta, phi, indexing="ij")
    verts = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], -1)
    verts[:, nu] = verts[:, 0]  # the seam: the same positions (sin 2 pi is not 0)
    verts = verts.reshape(-1, 3)
    faces = []
    for j in range(nv):
        for i in range(nu):
            a = j * (nu + 1) + i
            faces += [[a, a + 1, a + nu + 1], [a + 1, a + nu + 2, a + nu + 1]]  # outward
    faces.append([0, 0, 1])  # area 0
    ply.write(tmp_path / "ball.ply", verts, np.array(faces))
    placed = {"file": "ball.ply", "material": "red", **mesh}
    return write_scene(tmp_path, version=2, lights=[{"position": [-5, 5, -5]}],
                       camera={"eye": [0, 1, -5], "look_at": [0, 0, 0]},
                       materials={"red": {"color": [0.9, 0.2, 0.2], "specular": 0.5,
                                          "shininess": 20}},
                       planes=[{"point": [0, -1.2, 0], "normal": [0, 1, 0]}],
                       meshes=[placed],
                       triangles=[{"vertices": [[-2, -1, 1], [-1, -1, 1], [-1.5, 0.5, 1]]}])


def rtcl_triangle_count(scene, tmp_path):
    """How many triangles rtcl keeps (its -v line), or None without rtcl."""
    if not os.access(RTCL, os.X_OK):
        return None
    done = subprocess.run([RTCL, "-s", str(scene), "--size", "8x8", "-o",
                           str(tmp_path / "count.ppm"), "-v"],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    return int(re.search(r"rtcl: (\d+) triangles;", done.stderr).group(1))


def test_mesh_becomes_placed_mirrored_mesh2(tmp_path):
    scene = uv_ball_scene(tmp_path, smooth=False, translate=[0.5, 0, 0])
    text = sdl("-s", scene)
    m = re.search(r"^mesh2 \{  // (\d+) triangles\n  vertex_vectors \{ (\d+),\n(.*?)\n  \}\n"
                  r"  face_indices \{ (\d+),", text, re.M | re.S)
    assert m, text
    kept = int(m.group(1))
    # the poles' triangles of area 0 and the extra one dropped, as rtcl drops them
    assert kept == int(m.group(4)) < 12 * 8 * 2
    expected = rtcl_triangle_count(scene, tmp_path)
    if expected is not None:
        assert kept + 1 == expected  # rtcl's count includes the inline triangle
    vertices = [tuple(float(c) for c in v) for v in re.findall(VEC, m.group(3))]
    assert len(vertices) == int(m.group(2)) <= 13 * 9
    xs = [-v[0] for v in vertices]  # mirrored back into rtcl's x
    assert min(xs) == pytest.approx(-0.5) and max(xs) == pytest.approx(1.5)
    assert "normal_vectors" not in text
    tri = re.search(r"^triangle \{ (%s), (%s), (%s)" % (VEC, VEC, VEC), text, re.M)
    assert [float(tri.group(i)) for i in (2, 6, 10)] == [2, 1, 1.5]  # x mirrored


def test_smooth_mesh_has_one_normal_per_position(tmp_path):
    text = sdl("-s", uv_ball_scene(tmp_path))
    m = re.search(r"normal_vectors \{ (\d+),\n(.*?)\n  \}", text, re.S)
    assert m and int(m.group(1)) == 13 * 9  # every vertex's, no triangle's own needed
    normals = np.array([[float(c) for c in v] for v in re.findall(VEC, m.group(2))])
    assert np.linalg.norm(normals, axis=1) == pytest.approx(np.ones(len(normals)))
    # the seam's duplicated vertices (i = 0 and i = 12 of each ring) share one normal
    rings = normals.reshape(9, 13, 3)
    assert rings[:, 0] == pytest.approx(rings[:, 12])
    # on a ball the area-weighted normal points out from the centre (mirrored x)
    equator = rings[4, :12] * [-1, 1, 1]
    angles = 2 * np.pi * np.arange(12) / 12
    assert equator == pytest.approx(np.stack([np.cos(angles), 0 * angles, np.sin(angles)], -1),
                                    abs=1e-6)  # float vertices


@pytest.mark.parametrize("mesh", [{}, {"scale": [1, 1, -1], "rotate": [10, 30, 0]}])
def test_mesh_render_matches_rtcl(tmp_path, mesh):
    pov, ref = render_both(tmp_path, uv_ball_scene(tmp_path, **mesh), "96x72")
    same = (np.abs(pov - ref).max(axis=2) <= 2).mean()
    assert same > 0.99  # measured 99.87 % at 128x96 with the mirroring scale


def test_output_file_equals_stdout(tmp_path):
    out = tmp_path / "s.pov"
    done = run_tool("-s", "scenes/two_balls.json", "--size", "64x48", "-o", out)
    assert done.returncode == 0 and done.stdout == "" and done.stderr == ""
    assert out.read_text() == sdl("-s", "scenes/two_balls.json", "--size", "64x48")


# ---- errors -------------------------------------------------------------------------

def test_missing_scene_one_line_no_output(tmp_path):
    out = tmp_path / "s.pov"
    done = run_tool("-s", tmp_path / "nope.json", "-o", out)
    assert_one_line_error(done, "nope.json", "No such file")
    assert not out.exists() and done.stdout == ""


def test_missing_scene_with_time_and_image(tmp_path):
    image = tmp_path / "x.png"
    done = run_tool("-s", tmp_path / "nope.json", "--time", "1", "--image", image)
    assert_one_line_error(done, "nope.json")
    assert not image.exists()


def test_malformed_json_names_line_and_column(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{\n  "format": "rtcl-scene",\n  "version": 1,,\n}')
    assert_one_line_error(run_tool("-s", path), "bad.json: 3:")


@pytest.mark.parametrize("overrides, fragment", [
    ({"spheres": [{"center": [0, 0, 0], "radius": 1, "material": "gold"}]},
     'spheres[0].material: unknown material "gold"'),
    ({"spheres": [{"center": [0, 0, 0], "radius": -1}]}, "spheres[0].radius: must be > 0"),
    ({"spheres": [{"center": [0, 0, 0], "radus": 1}]}, 'spheres[0]: unknown key "radus"'),
    ({"version": 3}, "version: version 3 is not supported"),
    ({"version": 2, "meshes": [{"file": "scene.json"}]},
     "only the binary PLY meshes tools/genbench.py writes are converted"),
])
def test_bad_scene_one_line(tmp_path, overrides, fragment):
    out = tmp_path / "s.pov"
    assert_one_line_error(run_tool("-s", write_scene(tmp_path, **overrides), "-o", out), fragment)
    assert not out.exists()


@pytest.mark.parametrize("args", [("--time", "0"), ("--depth", "65"), ("--size", "0x5"),
                                  ("--image", "x.jpg")])
def test_bad_options_exit_2(args):
    done = run_tool(*args)
    assert done.returncode == 2 and done.stdout == ""
    assert "error:" in done.stderr


def test_unwritable_output_one_line(tmp_path):
    target = tmp_path / "no-such-dir" / "s.pov"
    assert_one_line_error(run_tool("-o", target), str(target), "No such file")


def test_fully_transparent_material_warns(tmp_path):
    path = write_scene(tmp_path, spheres=[{"center": [0, 0, 0], "radius": 1,
                                           "material": {"transmit": 1}}])
    done = run_tool("-s", path)
    assert done.returncode == 0
    assert done.stderr.count("\n") == 1 and "transmit 1" in done.stderr
    assert "finish { ambient 0 diffuse 0 specular 0.3 roughness 0.03125 }" in done.stdout


def test_missing_povray_executable(tmp_path):
    image = tmp_path / "x.png"
    done = run_tool("--povray", "no-such-povray", "--image", image)
    assert_one_line_error(done, "no-such-povray not found")
    assert not image.exists()


# ---- renders compared with rtcl -----------------------------------------------------

def read_ppm(path):
    """Pixels of a binary 8-bit PPM (comments allowed) as an (h, w, 3) int array."""
    (w, h), data = ppm.pixels(path)
    return np.frombuffer(data[:w * h * 3], np.uint8).reshape(h, w, 3).astype(int)


def render_both(tmp_path, scene, size, *extra):
    if not HAVE_POVRAY:
        pytest.skip("povray is not installed (apt-get install povray)")
    if not os.access(RTCL, os.X_OK):
        pytest.skip("no rtcl binary at %s (make)" % RTCL)
    pov, ref = tmp_path / "pov.ppm", tmp_path / "rtcl.ppm"
    done = run_tool("-s", scene, "--size", size, "--image", pov, *extra)
    assert done.returncode == 0, done.stderr
    assert re.search(r"POV-Ray trace time over 1 run\(s\): median [0-9.]+ s", done.stdout)
    # POV-Ray writes File_Gamma 1.0: the paper's linear bytes.
    rtcl = subprocess.run([RTCL, "-s", str(scene), "--size", size, "-o", str(ref),
                           "--encoding", "linear", *extra],
                          capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert rtcl.returncode == 0, rtcl.stderr
    return read_ppm(pov), read_ppm(ref)


def test_two_balls_render_matches_rtcl(tmp_path):
    pov, ref = render_both(tmp_path, SCENES / "two_balls.json", "64x48")
    assert pov.shape == ref.shape == (48, 64, 3)
    diff = np.abs(pov - ref)
    assert diff.mean() < 0.5                                   # measured 0.012
    assert (diff.max(axis=2) <= 2).mean() > 0.99               # measured 99.9 %
    # background (0.2, 0.25, 0.35) -> (51, 64, 89): the same pixels, the same values
    bg = np.array([51, 64, 89])
    pov_bg = (np.abs(pov - bg) <= 1).all(axis=2)
    ref_bg = (np.abs(ref - bg) <= 1).all(axis=2)
    assert ref_bg.sum() > 0.2 * ref_bg.size
    assert (pov_bg == ref_bg).all()
    # the balls' silhouettes: pixels strongly red or strongly blue, at the same places
    for channel in (0, 2):
        other = 2 - channel
        pov_ball = pov[..., channel] > pov[..., other] + 40
        ref_ball = ref[..., channel] > ref[..., other] + 40
        assert ref_ball.sum() > 50
        assert (pov_ball != ref_ball).sum() <= 2


@pytest.mark.parametrize("depth", ["0", "1"])
def test_paper60_shallow_render_identical_to_rtcl(tmp_path, depth):
    """At depth 0 and 1 nothing differs that 8 bits can see: the camera, the
    checker, the materials and the shadows (glass clones included) are exact."""
    pov, ref = render_both(tmp_path, SCENES / "paper60.json", "64x48", "--depth", depth)
    assert np.abs(pov - ref).max() <= 1


def test_time_reports_every_run(tmp_path):
    if not HAVE_POVRAY:
        pytest.skip("povray is not installed (apt-get install povray)")
    done = run_tool("-s", "scenes/two_balls.json", "--size", "32x24", "--time", "2")
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert re.search(r"^povray: POV-Ray 3\.7", out, re.M)
    assert "max_trace_level 6" in out
    assert re.search(r"command \(.*\): \S*povray \+Iscene\.pov \+Orender\.png \+W32 \+H24 -A "
                     r"\+WT2 -D \+FN File_Gamma=1\.0$", out, re.M)
    assert len(re.findall(r"^run \d: wall [0-9.]+ s, POV-Ray trace time", out, re.M)) == 2
    assert re.search(r"^wall time over 2 run\(s\): median [0-9.]+ s, min [0-9.]+ s, "
                     r"max [0-9.]+ s$", out, re.M)
