"""The command line's camera (--eye, --look-at, --fov, --aperture,
--focus-distance) and issue 27's scene features end to end: what works, that
their defaults leave images byte for byte as they were, and one clear message
for every bad value (docs/SCENE.md, docs/RENDERING.md)."""
import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SMALL = ["--size", "24x16"]


def rtcl(*args, cwd=None):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=cwd or ROOT,
                          timeout=300)


def render(tmp_path, name, *args):
    out = tmp_path / name
    result = rtcl("-q", *SMALL, "-o", str(out), *args)
    assert result.returncode == 0, result.stderr
    return out.read_bytes()


def build_options(tmp_path, *args):
    result = rtcl("-v", *SMALL, "-o", str(tmp_path / "v.png"), *args)
    assert result.returncode == 0, result.stderr
    return next(line for line in result.stderr.splitlines() if "build options:" in line)


def write_scene(tmp_path, name, **changes):
    doc = json.loads((ROOT / "scenes" / "two_balls.json").read_text())
    for key, value in changes.items():
        section, _, field = key.partition("__")
        if field:
            doc[section][field] = value
        else:
            doc[section] = value
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return str(path)


def test_help_teaches_the_camera_options():
    text = rtcl("--help").stdout
    for option in ("--eye X,Y,Z", "--look-at X,Y,Z", "--fov DEG", "--aperture A",
                   "--focus-distance F"):
        assert option in text, option


def test_camera_options_override_the_scene(tmp_path):
    scene = str(ROOT / "scenes" / "two_balls.json")
    moved = write_scene(tmp_path, "moved.json",
                        camera={"eye": [1, 3, -6], "look_at": [0, 0.5, 0], "fov": 30})
    want = render(tmp_path, "scene.pfm", moved)
    got = render(tmp_path, "options.pfm", scene, "--eye", "1,3,-6", "--look-at", "0,0.5,0",
                 "--fov", "30")
    assert got == want
    assert render(tmp_path, "plain.pfm", scene) != want


def test_aperture_0_is_the_pinhole_program_and_image(tmp_path):
    """The pinhole is built without the lens code (-DRTCL_THIN_LENS): the program and
    image of before depth of field existed, byte for byte."""
    scene = str(ROOT / "scenes" / "two_balls.json")
    zero = write_scene(tmp_path, "zero.json",
                       camera={"eye": [0, 2.2, -7.5], "look_at": [0, 1, 0], "aperture": 0,
                               "focus_distance": 3})
    plain = render(tmp_path, "plain.pfm", scene, "--spp", "2")
    assert render(tmp_path, "zero.pfm", zero, "--spp", "2") == plain
    assert render(tmp_path, "opt.pfm", scene, "--spp", "2", "--aperture", "0") == plain
    assert "RTCL_THIN_LENS" not in build_options(tmp_path, scene, "--aperture", "0")
    assert "RTCL_THIN_LENS" in build_options(tmp_path, scene, "--aperture", "0.2")


def test_aperture_blurs_and_the_focus_distance_matters(tmp_path):
    scene = str(ROOT / "scenes" / "two_balls.json")
    plain = render(tmp_path, "plain.pfm", scene, "--spp", "2")
    lens = render(tmp_path, "lens.pfm", scene, "--spp", "2", "--aperture", "0.3")
    near = render(tmp_path, "near.pfm", scene, "--spp", "2", "--aperture", "0.3",
                  "--focus-distance", "3")
    assert len({plain, lens, near}) == 3


@pytest.mark.parametrize("args, message", [
    (["--eye", "1,2"], '--eye: expected X,Y,Z, three numbers each 0 or of a magnitude between '
                       '1e-18 and 1e18 (e.g. 0,6,-24), got "1,2"'),
    (["--eye", "1,2,3,4"], '--eye: expected X,Y,Z'),
    (["--look-at", "1,x,3"], '--look-at: expected X,Y,Z'),
    (["--look-at", "1,nan,3"], '--look-at: expected X,Y,Z'),
    (["--eye", "1e19,0,0"], '--eye: expected X,Y,Z'),
    (["--fov", "0"], '--fov: expected degrees, a number greater than 0 and less than 180, '
                     'got "0"'),
    (["--fov", "180"], '--fov: expected degrees'),
    (["--fov", "wide"], '--fov: expected degrees'),
    (["--aperture", "-1"], '--aperture: expected the lens radius, a number >= 0 (0: a pinhole; '
                           'else between 1e-18 and 1e18), got "-1"'),
    (["--focus-distance", "0"], '--focus-distance: expected a distance > 0 (between 1e-18 and '
                                '1e18), got "0"'),
    (["--focus-distance", "inf"], '--focus-distance: expected a distance > 0'),
    (["--eye", "0,1,0", "--look-at", "0,1,0"],
     "--eye and --look-at: camera.look_at must differ from camera.eye, both are [0, 1, 0]"),
    (["--eye", "0,5,0", "--look-at", "0,1,0"],
     "--eye and --look-at: camera.up must not be parallel to look_at - eye, got [0, 1, 0]"),
])
def test_bad_camera_option(tmp_path, args, message):
    out = tmp_path / "out"
    out.mkdir()
    result = rtcl("-o", str(out / "out.png"), *args)
    assert result.returncode == 2, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rtcl: ") and message in lines[0], lines
    assert result.stdout == ""
    assert os.listdir(out) == [], "a refused run left files behind"


def test_radius_0_is_the_point_light_program_and_image(tmp_path):
    """Lights of radius 0 build without light samples (-DRTCL_AREA_LIGHTS): the image of
    point lights, byte for byte; a radius or a directional light samples them."""
    scene = str(ROOT / "scenes" / "two_balls.json")
    lights = json.loads((ROOT / "scenes" / "two_balls.json").read_text())["lights"]
    zero = write_scene(tmp_path, "zero.json", lights=[dict(li, radius=0) for li in lights])
    sphere = write_scene(tmp_path, "sphere.json",
                         lights=[dict(lights[0], radius=1), lights[1]])
    sun = write_scene(tmp_path, "sun.json",
                      lights=[lights[0], {"direction": [-1, -2, 1], "angle": 2}])
    plain = render(tmp_path, "plain.pfm", scene, "--spp", "2")
    assert render(tmp_path, "zero.pfm", zero, "--spp", "2") == plain
    assert "RTCL_AREA_LIGHTS" not in build_options(tmp_path, zero)
    for name, path in (("sphere", sphere), ("sun", sun)):
        assert "RTCL_AREA_LIGHTS" in build_options(tmp_path, path)
        assert render(tmp_path, name + ".pfm", path, "--spp", "2") != plain


def test_fresnel_false_is_the_program_and_image_of_before(tmp_path):
    """Without a Fresnel material the program keeps numbers for weights (no
    -DRTCL_FRESNEL) and the image is byte for byte the one of before."""
    scene = str(ROOT / "scenes" / "two_balls.json")
    materials = json.loads((ROOT / "scenes" / "two_balls.json").read_text())["materials"]
    off = write_scene(tmp_path, "off.json",
                      materials={k: dict(v, fresnel=False) for k, v in materials.items()})
    on = write_scene(tmp_path, "on.json",
                     materials={k: dict(v, fresnel="dielectric") for k, v in materials.items()})
    plain = render(tmp_path, "plain.pfm", scene)
    assert render(tmp_path, "off.pfm", off) == plain
    assert "RTCL_FRESNEL" not in build_options(tmp_path, off)
    assert "RTCL_FRESNEL" in build_options(tmp_path, on)
    assert render(tmp_path, "on.pfm", on) != plain


# make test-long: test_lens_lights.c's studio test renders it with every kernel
# and the reference in make test.
@pytest.mark.slow
def test_studio_renders_with_every_kernel(tmp_path):
    for kernel in ("dynamic", "wavefront", "reference"):
        assert render(tmp_path, kernel + ".png", str(ROOT / "scenes" / "studio.json"),
                      "-k", kernel, "--spp", "2")
