"""The Python scene validator (tools/rtcl_tools/scene.py) on format version 2 and
image.samples: good version 2 scenes read with SCENE.md's defaults. Its bad scenes
are rtcl's, in test/bad_scenes/ (test/test_rtcl_tools.py)."""
import pathlib
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import scene  # noqa: E402

CAMERA = {"eye": [0, 1, -5], "look_at": [0, 1, 0]}
TRIANGLE = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]


def v2(**fields):
    doc = {"format": "rtcl-scene", "version": 2, "camera": CAMERA}
    doc.update(fields)
    return doc


def test_mesh_defaults_and_file_relative_to_the_scene(tmp_path):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "m.ply").write_bytes(b"ply\n")
    path = tmp_path / "scene.json"
    path.write_text('{"format": "rtcl-scene", "version": 2, "camera": {"eye": [0, 1, -5], '
                    '"look_at": [0, 1, 0]}, "meshes": [{"file": "models/m.ply"}, '
                    '{"file": "models/m.ply", "scale": [1, -2, 3], "rotate": [0, 90, 0], '
                    '"translate": [1, 2, 3], "smooth": false, "material": {"reflect": 1}}]}')
    loaded = scene.load_scene(path)
    first, second = loaded["meshes"]
    assert first["file"] == str(tmp_path / "models" / "m.ply")
    assert (first["scale"], first["rotate"], first["translate"], first["smooth"]) == \
        ((1, 1, 1), (0, 0, 0), (0, 0, 0), True)
    assert first["material"] == scene.MATERIAL_DEFAULTS
    assert (second["scale"], second["rotate"], second["translate"], second["smooth"]) == \
        ((1, -2, 3), (0, 90, 0), (1, 2, 3), False)
    assert second["material"]["reflect"] == 1
    assert loaded["version"] == 2 and loaded["triangles"] == []


def test_the_mesh_file_is_looked_up_beside_the_scene_not_the_working_folder(tmp_path,
                                                                            monkeypatch):
    (tmp_path / "m.obj").write_text("v 0 0 0\n")
    (tmp_path / "sub").mkdir()
    scene_path = tmp_path / "sub" / "scene.json"
    scene_path.write_text('{"format": "rtcl-scene", "version": 2, "camera": {"eye": [0, 1, -5],'
                          ' "look_at": [0, 1, 0]}, "meshes": [{"file": "m.obj"}]}')
    monkeypatch.chdir(tmp_path)
    with pytest.raises(scene.SceneError, match='meshes\\[0\\].file: cannot read "m.obj"'):
        scene.load_scene(scene_path)


def test_an_absolute_mesh_path_is_used_as_it_is(tmp_path):
    mesh = tmp_path / "m.obj"
    mesh.write_text("v 0 0 0\n")
    loaded = scene.read_scene(v2(meshes=[{"file": str(mesh), "scale": 2}]), "/nonexistent")
    assert loaded["meshes"][0]["file"] == str(mesh)
    assert loaded["meshes"][0]["scale"] == (2, 2, 2)


def test_without_a_folder_mesh_files_are_not_looked_up():
    loaded = scene.read_scene(v2(meshes=[{"file": "nowhere.ply"}]))
    assert loaded["meshes"][0]["file"] == "nowhere.ply"


def test_inline_triangles_read_with_their_material():
    loaded = scene.read_scene(v2(materials={"red": {"color": [1, 0, 0]}},
                                 triangles=[{"vertices": TRIANGLE, "material": "red"},
                                            {"vertices": TRIANGLE}]))
    first, second = loaded["triangles"]
    assert first["vertices"] == ((0, 0, 0), (1, 0, 0), (0, 1, 0))
    assert first["material"]["color"] == (1, 0, 0)
    assert second["material"] == scene.MATERIAL_DEFAULTS


def test_a_tiny_but_nonzero_triangle_is_accepted():
    tiny = [[0, 0, 0], [1e-9, 0, 0], [0, 1e-9, 0]]
    assert scene.read_scene(v2(triangles=[{"vertices": tiny}]))["triangles"]


@pytest.mark.parametrize("version", [1, 2])
def test_samples_default_and_read(version):
    doc = v2(version=version)
    assert scene.read_scene(doc)["samples"] == 1
    doc["image"] = {"samples": 65536}
    assert scene.read_scene(doc)["samples"] == 65536


@pytest.mark.parametrize("version, message", [
    (0, "version: must be 1 or 2, got 0"),
    (3, "version: version 3 is not supported (this rtcl reads versions 1 and 2)")])
def test_other_versions_are_refused(version, message):
    with pytest.raises(scene.SceneError) as caught:
        scene.read_scene(v2(version=version))
    assert str(caught.value) == message


def test_version_1_is_read_as_before():
    loaded = scene.read_scene(v2(version=1, spheres=[{"center": [0, 0, 0], "radius": 1}]))
    assert loaded["meshes"] == [] and loaded["triangles"] == [] and loaded["version"] == 1
