"""Small objects far from the origin (issue 24, finding 9): the device renders
relative to the camera's eye (RENDERING.md, "Coordinates on the device"), so
a unit sphere at x = 1e7 or 1e15 seen from 10 units renders as it does at the
origin, and what float still cannot resolve is refused with the numbers."""
import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))


def far_scene(directory, x, name, checker=False, radius=1.0, eye_distance=10.0):
    """A unit sphere at (x, 0, 0), the eye eye_distance in front of it, a
    light beside the eye; with checker, a checkered floor under it."""
    scene = {"format": "rtcl-scene", "version": 1, "image": {"width": 48, "height": 36},
             "camera": {"eye": [x, 0, -eye_distance], "look_at": [x, 0, 0], "fov": 30},
             "background": [0.1, 0.1, 0.1], "ambient": [0.1, 0.1, 0.1], "max_depth": 3,
             "materials": {"m": {"color": [0.8, 0.3, 0.2], "diffuse": 0.7, "specular": 0.3}},
             "lights": [{"position": [x - 5, 5, -10]}],
             "spheres": [{"center": [x, 0, 0], "radius": radius, "material": "m"}]}
    if checker:
        scene["planes"] = [{"point": [0, -1, 0], "normal": [0, 1, 0], "material": "m",
                            "checker": {"size": 0.5, "color": [0.9, 0.9, 0.9]}}]
    path = directory / f"{name}.json"
    path.write_text(json.dumps(scene))
    return path


def render(scene, out, *args):
    result = subprocess.run([RTCL, "-q", "-s", str(scene), "-o", str(out), *args],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return out


def pfm_values(path):
    np = pytest.importorskip("numpy")
    header = path.read_bytes().split(b"\n", 3)
    width, height = map(int, header[1].split())
    return np.frombuffer(header[3], dtype="<f4").reshape(height, width, 3)


@pytest.mark.parametrize("x", [1e7, 1e15])
def test_a_unit_sphere_far_from_the_origin_renders_close_to_the_reference(tmp_path, x):
    np = pytest.importorskip("numpy")
    scene = far_scene(tmp_path, x, "far")
    image = pfm_values(render(scene, tmp_path / "far.pfm"))
    reference = pfm_values(render(far_scene(tmp_path, 0.0, "near"), tmp_path / "ref.pfm",
                                  "-k", "reference"))
    # Before: a ragged shape with radiance up to 11.5 at 1e7, all black at 1e15.
    assert image.max() < 1.0
    off = np.abs(image - reference).max(axis=2) > 0.01
    assert off.sum() <= 0.01 * off.size, f"{off.sum()} pixels differ from the reference"
    if x == 1e7:  # double still resolves the scene there: the reference agrees
        far_reference = pfm_values(render(scene, tmp_path / "far_ref.pfm", "-k", "reference"))
        assert (np.abs(image - far_reference).max(axis=2) > 0.01).sum() <= 0.01 * off.size


def test_the_device_image_does_not_depend_on_where_the_scene_lies(tmp_path):
    # Relative to the eye, the scene at 1e7 is the scene at 0, byte for byte,
    # the checkered floor included (its squares stay where the world has them).
    near = render(far_scene(tmp_path, 0.0, "near", checker=True), tmp_path / "near.pfm")
    far = render(far_scene(tmp_path, 1e7, "far", checker=True), tmp_path / "far.pfm")
    assert near.read_bytes() == far.read_bytes()


def test_an_object_below_float_resolution_at_its_distance_is_refused(tmp_path):
    scene = far_scene(tmp_path, 0.0, "tiny", radius=1e-6, eye_distance=1e7)
    result = subprocess.run([RTCL, "-s", str(scene), "-o", str(tmp_path / "x.png")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 1
    (line,) = result.stderr.splitlines()
    assert line == (f"rtcl: {scene}: spheres[0]: the radius 1e-06 at 1e+07 from the eye is "
                    "below what float resolves there (4 steps of 1): rtcl renders in float "
                    "relative to the eye; move the camera closer or enlarge the object"), line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tiny.json"]


@pytest.mark.parametrize("x", [1e13, 1e15])
def test_the_reference_image_does_not_depend_on_where_the_scene_lies(tmp_path, x):
    """The reference renders relative to the eye too, in double (issue 39 finding 8):
    in world coordinates the shadow rays' offset of 1e-4 vanished at 1e13 and the
    sphere shadowed itself. Its numbers relative to the eye are those of the scene
    at 0 exactly, and so are the images."""
    near = render(far_scene(tmp_path, 0.0, "near"), tmp_path / "near.pfm", "-k", "reference")
    far = render(far_scene(tmp_path, x, "far"), tmp_path / "far.pfm", "-k", "reference")
    assert near.read_bytes() == far.read_bytes()


def path_far_scene(directory, x, name):
    """far_scene's sphere under the path integrator, lit by every kind of
    light: an emitting triangle and an emitting sphere beside it, a sphere
    light, a directional light with an angle and a uniform environment, over
    a floor. Every position is x plus a multiple of 1/2, exact in double at
    1e15, so relative to the eye the scene is the one at 0."""
    scene = {"format": "rtcl-scene", "version": 2, "integrator": "path", "max_depth": 3,
             "image": {"width": 32, "height": 24, "samples": 4},
             "camera": {"eye": [x, 0, -10], "look_at": [x, 0, 0], "fov": 40},
             "background": [0.05, 0.05, 0.1],
             "materials": {
                 "m": {"bsdf": {"type": "diffuse", "reflectance": [0.8, 0.3, 0.2]}},
                 "gold": {"bsdf": {"type": "conductor", "reflectance": [1.0, 0.78, 0.34],
                                   "roughness": 0.3}},
                 "lamp": {"bsdf": {"type": "diffuse", "reflectance": [0, 0, 0]},
                          "emission": [6, 5, 4]}},
             "lights": [{"position": [x - 5, 5, -10], "radius": 0.5, "color": [20, 20, 20]},
                        {"direction": [1, -1, 1], "angle": 2, "color": [0.5, 0.5, 0.5]}],
             "spheres": [{"center": [x, 0, 0], "radius": 1, "material": "m"},
                         {"center": [x + 2, 1, 1], "radius": 0.5, "material": "lamp"},
                         {"center": [x - 2, 0, 1], "radius": 0.5, "material": "gold"}],
             "triangles": [{"vertices": [[x - 1, 3, -1], [x + 1, 3, -1], [x + 1, 3, 1]],
                            "material": "lamp"}],
             "planes": [{"point": [x, -1, 0], "normal": [0, 1, 0], "material": "m"}]}
    path = directory / f"{name}.json"
    path.write_text(json.dumps(scene))
    return path


@pytest.mark.parametrize("x", [1e13, 1e15])
def test_the_path_reference_image_does_not_depend_on_where_the_scene_lies(tmp_path, x):
    """The reference's path integrator works relative to the eye as its
    Whitted one does: its emitters, lights, floor and camera are the scene's
    at 0, byte for byte, and so is the image (in world coordinates the
    sphere at 1e15 is a blur of 1/8 steps, its shadow rays start inside it
    and the emitters' sample points round)."""
    near = render(path_far_scene(tmp_path, 0.0, "near"), tmp_path / "near.pfm",
                  "-k", "reference")
    far = render(path_far_scene(tmp_path, x, "far"), tmp_path / "far.pfm", "-k", "reference")
    assert near.read_bytes() == far.read_bytes()
