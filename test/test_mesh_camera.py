"""The camera from a mesh file (docs/SCENE.md, "The camera from a mesh file"): a
mesh entry's "camera" makes its glTF file's camera the scene's view, its node
hierarchy and the entry's placement applied; the conflicts and errors are one
message each; -v says which camera came from which file."""
import base64
import json
import math
import os
import pathlib
import re
import struct
import subprocess

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SIZE = "16x12"


def rtcl(*args):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


def gltf(nodes, cameras):
    """A glTF of one quad and one triangle (so that a wrong view shows), node 0 the
    mesh, then `nodes`, all in the scene's roots but children."""
    points = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0), (0.2, 0.2, 0.5),
              (0.8, 0.2, 0.5), (0.5, 0.8, 0.5)]
    blob = b"".join(struct.pack("<3f", *p) for p in points)
    index_at = len(blob)
    blob += struct.pack("<9H", 0, 1, 2, 0, 2, 3, 4, 5, 6) + b"\0\0"
    children = {c for n in nodes for c in n.get("children", [])}
    return {"asset": {"version": "2.0"}, "scene": 0,
            "scenes": [{"nodes": [i for i in range(len(nodes) + 1) if i not in children]}],
            "nodes": [{"mesh": 0}] + nodes, "cameras": cameras,
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                         + base64.b64encode(blob).decode()}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": index_at},
                            {"buffer": 0, "byteOffset": index_at, "byteLength": 18}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 7, "type": "VEC3",
                           "min": [-1, -1, 0], "max": [1, 1, 0.5]},
                          {"bufferView": 1, "componentType": 5123, "count": 9,
                           "type": "SCALAR"}]}


PERSPECTIVE = {"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 1.5,
                                                      "znear": 0.1}}
ORTHOGRAPHIC = {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1,
                                                         "zfar": 10}}
# "Cam" (node 2) is a child of "Rig" (node 1), turned 180 degrees about y: it looks
# down +z from (0.5, 0, -4) in the file's world.
NODES = [{"name": "Rig", "translation": [0.5, 0, 0], "children": [2]},
         {"name": "Cam", "camera": 0, "rotation": [0, 1, 0, 0], "translation": [0, 0, -4]},
         {"name": "Top", "camera": 1, "translation": [0, 5, 0]}]


def scene(tmp_path, meshes, camera=None, doc=None, name="s.json"):
    (tmp_path / "c.gltf").write_text(json.dumps(doc or gltf(NODES, [PERSPECTIVE, ORTHOGRAPHIC])))
    scene = {"format": "rtcl-scene", "version": 2, "lights": [{"position": [0, 3, 6]}],
             "meshes": meshes}
    if camera is not None:
        scene["camera"] = camera
    path = tmp_path / name
    path.write_text(json.dumps(scene))
    return path


def render(path, *options):
    out = path.with_suffix(".ppm")
    result = rtcl(path, "-o", out, "--size", SIZE, *options)
    assert result.returncode == 0, result.stderr
    pixels = out.read_bytes()[-16 * 12 * 3:]  # past the header, which names the scene
    assert len(set(pixels)) > 2, "the mesh is not in view"
    return pixels, result.stderr


def camera_line(err):
    found = re.search(r'camera "([^"]*)": eye \[(.*?)\], look_at \[(.*?)\], up \[(.*?)\], '
                      r"fov (\S+)", err)
    assert found, err
    vec = lambda text: [float(x) for x in text.split(", ")]  # noqa: E731
    return (found.group(1), vec(found.group(2)), vec(found.group(3)), vec(found.group(4)),
            float(found.group(5)))


def test_the_file_camera_renders_as_the_same_camera_written_in_the_scene(tmp_path):
    """The node hierarchy, then the entry's scale 2, rotate 180 about y and translate:
    eye (-1, 0.25, 8) looking down -z, exactly; the same camera written in the scene
    renders the same bytes."""
    path = scene(tmp_path, [{"file": "c.gltf", "camera": "Cam", "scale": 2,
                             "rotate": [0, 180, 0], "translate": [0, 0.25, 0]}])
    image, err = render(path, "-v")
    name, eye, look_at, up, fov = camera_line(err)
    assert (name, eye, look_at, up) == ("Cam", [-1, 0.25, 8], [-1, 0.25, 7], [0, 1, 0])
    assert 'rtcl: meshes[0] "c.gltf": camera "Cam": eye [-1, 0.25, 8]' in err
    # yfov, not Assimp's horizontal angle (0.7 * 1.5 in Assimp 5.2)
    assert abs(fov - math.degrees(0.7)) < 1e-4, fov
    written = scene(tmp_path, [{"file": "c.gltf", "scale": 2, "rotate": [0, 180, 0],
                                "translate": [0, 0.25, 0]}],
                    camera={"eye": eye, "look_at": look_at, "up": up, "fov": fov},
                    name="w.json")
    assert render(written)[0] == image


def test_camera_true_takes_the_first_and_the_command_line_still_applies(tmp_path):
    """Without an aspect ratio the fov is yfov; the scene's camera gives the lens;
    --fov overrides the file's."""
    doc = gltf([{"name": "Only", "camera": 0, "translation": [0, 0, 5]}],
               [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}])
    path = scene(tmp_path, [{"file": "c.gltf", "camera": True}],
                 camera={"aperture": 0, "focus_distance": 5}, doc=doc)
    image, err = render(path, "-v", "--fov", "40")
    name, eye, look_at, up, fov = camera_line(err)
    assert (name, eye, look_at, up) == ("Only", [0, 0, 5], [0, 0, 4], [0, 1, 0])
    assert abs(fov - math.degrees(0.5)) < 1e-4, fov
    written = scene(tmp_path, [{"file": "c.gltf"}],
                    camera={"eye": eye, "look_at": look_at, "fov": 40}, doc=doc,
                    name="w.json")
    assert render(written)[0] == image


def refused(path):
    out = path.with_suffix(".png")
    result = rtcl(path, "-o", out)
    assert result.returncode == 1, result.stderr
    assert not out.exists()
    assert result.stderr.count("\n") == 1, result.stderr
    return result.stderr.rstrip("\n")


def test_a_file_without_a_camera_is_refused(tmp_path):
    path = scene(tmp_path, [{"file": str(ROOT / "test" / "meshes" / "cube.obj"),
                             "camera": True}])
    assert refused(path) == f'{path}: meshes[0].camera: "{ROOT}/test/meshes/cube.obj" has no camera'


def test_an_unknown_camera_name_lists_the_files(tmp_path):
    path = scene(tmp_path, [{"file": "c.gltf", "camera": "cam"}])
    assert refused(path) == (f'{path}: meshes[0].camera: "c.gltf" has no camera "cam"; its '
                             'cameras are "Cam", "Top"')


def test_an_orthographic_camera_is_refused(tmp_path):
    path = scene(tmp_path, [{"file": "c.gltf", "camera": "Top"}])
    assert refused(path) == (f'{path}: meshes[0].camera: "c.gltf": camera "Top" is '
                             "orthographic; rtcl renders only perspective cameras")


def test_two_meshes_may_not_both_give_the_camera(tmp_path):
    path = scene(tmp_path, [{"file": "c.gltf", "camera": True},
                            {"file": "c.gltf", "camera": "Cam"}])
    assert refused(path) == (f"{path}: meshes[1].camera: meshes[0] gives the camera already; "
                             "one mesh at most may")


def test_the_scenes_camera_may_not_give_the_view_too(tmp_path):
    path = scene(tmp_path, [{"file": "c.gltf", "camera": True}],
                 camera={"eye": [0, 0, 5], "look_at": [0, 0, 0]})
    assert refused(path) == (f"{path}: camera.eye: the view comes from the camera of "
                             "meshes[0]'s file; the scene's \"camera\" may give only "
                             "\"aperture\" and \"focus_distance\" then")


def test_camera_must_be_true_false_or_a_name(tmp_path):
    path = scene(tmp_path, [{"file": "c.gltf", "camera": 1}])
    assert refused(path) == (f"{path}: meshes[0].camera: must be true, false or the name of "
                             "a camera of the file, got an integer")
    path = scene(tmp_path, [{"file": "c.gltf", "camera": ""}])
    assert refused(path) == f'{path}: meshes[0].camera: must name a camera of the file, got ""'


def test_camera_false_keeps_the_scenes_camera(tmp_path):
    """"camera": false is as if it were left out: the scene's camera is required."""
    path = scene(tmp_path, [{"file": "c.gltf", "camera": False}])
    assert refused(path) == f"{path}: camera: required field is missing"
