"""Issue 41's path-traced study scenes: the lake with glass (rtcl-genbench
lake-path) and scenes/materials_path.json render through rtcl on any device,
and tools/build/mitsuba_ref.py reads them for Mitsuba (its PLY meshes, an
OBJ's own textured MTL materials) or refuses, with a message, what it cannot
map. Mitsuba itself is not needed: the shapes and materials are checked as
the converter reads them (docs/oracle.md, "Mappings")."""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(ROOT / "tools" / "build"))
import mitsuba_ref  # noqa: E402

MATERIALS = ROOT / "scenes" / "materials_path.json"


def render(scene, out, *args):
    done = subprocess.run([RTCL, str(scene), "-o", str(out), *map(str, args)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "warning" not in done.stderr, done.stderr
    return done


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        width, height = map(int, f.readline().split())
        f.readline()
        return np.frombuffer(f.read(), dtype="<f4").reshape(height, width, 3)[::-1]


@pytest.fixture(scope="module")
def lake_path(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lake_path")
    subprocess.run([sys.executable, str(ROOT / "tools" / "genbench.py"), "lake-path", "--size",
                    "3", "-o", str(folder)], check=True, capture_output=True)
    return folder / "lake-path-3.json"


def test_the_lake_path_traced_has_glass_a_mirror_lake_and_the_sun(lake_path):
    doc = json.loads(lake_path.read_text())
    assert doc["integrator"] == "path" and doc["max_depth"] == 8 and "ambient" not in doc
    bsdfs = {name: m["bsdf"]["type"] for name, m in doc["materials"].items()}
    assert bsdfs == {"glass": "dielectric", "mountain": "diffuse", "lake": "conductor"}
    assert [s["material"] for s in doc["spheres"]] == ["glass"] * 4
    assert [t["material"] for t in doc["triangles"]] == ["lake", "lake"]
    assert "direction" in doc["lights"][0]


@pytest.mark.slow  # make test's 3 minutes
def test_the_lake_path_traced_renders_and_maps_to_mitsuba(lake_path, tmp_path):
    out = tmp_path / "lake.pfm"
    render(lake_path, out, "--size", "24x24", "--spp", "2")
    image = read_pfm(out)
    sky = np.array(json.loads(lake_path.read_text())["background"], dtype=np.float32)
    assert np.isfinite(image).all()
    assert (np.abs(image - sky).max(axis=2) > 0.02).mean() > 0.2  # the mountain shows
    shapes = list(mitsuba_ref.Scene(lake_path).shapes())
    triangles = sum(len(g) for kind, g, _, _ in shapes if kind == "triangles")
    assert triangles == 2 * 4 ** 3 + 2                               # the mountain, the lake
    assert sum(kind == "sphere" for kind, *_ in shapes) == 4
    for kind, geometry, (name, material), where in shapes:
        assert "bsdf" in material, where


def test_the_materials_scene_renders_nine_kinds_of_material():
    doc = json.loads(MATERIALS.read_text())
    kinds = set()
    for material in doc["materials"].values():
        bsdf = material["bsdf"]
        kind = bsdf["type"]
        if kind in ("conductor", "dielectric"):
            kind += " rough" if bsdf.get("roughness", 0) > 0 else " smooth"
        if kind == "principled":
            kind += (" metallic" if bsdf.get("metallic", 0) > 0 else
                     " transmitting" if bsdf.get("transmission", 0) > 0 else " plastic")
        if any(material.get("emission", [0, 0, 0])):
            kind = "emitter"
        kinds.add(kind)
    kinds.add("textured diffuse (MTL map_Kd)")  # the floor and the crate, below
    assert len(kinds) >= 9, kinds


@pytest.mark.slow
def test_the_materials_scene_renders_its_textures(tmp_path):
    out = tmp_path / "m.pfm"
    done = render(MATERIALS, out, "--size", "32x20", "--spp", "2", "-v")
    assert "1 texture" in done.stderr        # tiles.png and crate.png, a mesh each
    image = read_pfm(out)
    assert np.isfinite(image).all() and image.mean() > 0.05


def test_the_materials_scene_maps_its_textured_meshes_to_mitsuba():
    shapes = list(mitsuba_ref.Scene(MATERIALS).shapes())
    textured = [(g, m) for kind, g, (_, m), _ in shapes
                if kind == "triangles" and "mtl_diffuse" in m]
    assert len(textured) == 2                   # the floor and the crate
    for (triangles, uv), material in textured:
        assert uv.shape == (len(triangles), 3, 2)
        assert material["mtl_diffuse"]["texture"].is_file()
    floor_uv = textured[0][0][1]
    assert floor_uv.min() == 0 and floor_uv.max() == 4   # tiles.png repeated 4 times


@pytest.mark.parametrize("change, message", [
    (lambda folder: (folder / "m.mtl").write_text("newmtl m\nKd 1 1 1\nKs 1 1 1\nillum 3\n"),
     "only opaque MTL materials without reflection"),
    (lambda folder: (folder / "m.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd -s 2 2 t.png\n"),
     "map_Kd options are not mapped"),
    (lambda folder: (folder / "m.mtl").write_text("newmtl m\nKd 1 1 1\nKe 1 1 1\n"),
     "MTL statements the oracle does not map: ['Ke']"),
])
def test_the_converter_refuses_mtl_materials_it_cannot_map(tmp_path, change, message):
    (tmp_path / "m.obj").write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n"
                                    "usemtl m\nf 1/1 2/1 3/1\n")
    change(tmp_path)
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({"integrator": "path", "camera": {"eye": [0, 0, 1],
                                                                   "look_at": [0, 0, 0]},
                                 "meshes": [{"file": "m.obj", "smooth": False}]}))
    with pytest.raises(mitsuba_ref.SceneError, match=message.replace("[", r"\[")):
        list(mitsuba_ref.Scene(scene).shapes())


def test_the_converter_refuses_a_ply_mesh_without_a_material(lake_path, tmp_path):
    doc = json.loads(lake_path.read_text())
    del doc["meshes"][0]["material"]
    scene = lake_path.parent / "no_material.json"
    scene.write_text(json.dumps(doc))
    with pytest.raises(mitsuba_ref.SceneError, match="a PLY file has no materials"):
        list(mitsuba_ref.Scene(scene).shapes())


STUDIO = ROOT / "scenes" / "studio_path.json"


def test_the_converter_refuses_the_studio_plane_unless_asked_to_approximate():
    with pytest.raises(mitsuba_ref.SceneError,
                       match=r"planes: not mapped \(infinite; give triangles\)"):
        mitsuba_ref.Scene(STUDIO)
    shapes = list(mitsuba_ref.Scene(STUDIO, approximate=True).shapes())
    assert [kind for kind, *_ in shapes].count("sphere") == 5
    # The glTF trellis: its quad (x -0.5 ... 0.5, y 0 ... 1) scaled by [6, 2.4, 1],
    # turned 90 degrees about y (x becomes -z) and moved to [-3.3, 0, 1.5].
    (trellis,) = [g for kind, g, (name, _), where in shapes if where == "meshes[1]"]
    tri, uv = trellis
    assert tri.shape == (2, 3, 3)
    np.testing.assert_allclose(tri.reshape(-1, 3).min(axis=0), [-3.3, 0, -1.5], atol=1e-12)
    np.testing.assert_allclose(tri.reshape(-1, 3).max(axis=0), [-3.3, 2.4, 4.5], atol=1e-12)
    # The lattice texture repeated twice, v as rtcl reads it: 1 - glTF's v.
    assert sorted(set(uv[..., 0].ravel())) == [0, 2] and sorted(set(uv[..., 1].ravel())) == [-1, 1]
    # The floor: a 1000-unit square on y = 0 whose texture coordinates put
    # Mitsuba's checkerboard squares (u mod 1 > 0.5 against v mod 1 > 0.5, v
    # written as 1 - v) where rtcl's odd squares are: floor(x) + floor(z) odd.
    (floor,) = [(g, m) for kind, g, (_, m), where in shapes if where == "planes[0]"]
    (tri, uv), material = floor
    assert material["checker"] == [0.25, 0.25, 0.28]
    corners = tri.reshape(-1, 3)
    np.testing.assert_allclose(np.ptp(corners, axis=0), [1000, 0, 1000])
    rng = np.random.default_rng(1)
    for t, tuv in zip(tri, uv):
        w = rng.dirichlet([1, 1, 1], size=2000)
        points, coords = w @ t, w @ tuv
        coords[:, 1] = 1 - coords[:, 1]
        mitsuba_odd = (coords[:, 0] % 1 > 0.5) != (coords[:, 1] % 1 > 0.5)
        rtcl_odd = (np.floor(points[:, 0]) + np.floor(points[:, 2])) % 2 == 1
        assert (mitsuba_odd == rtcl_odd).mean() > 0.999    # all but float ties


def test_the_thin_lens_maps_to_mitsubas_thinlens(tmp_path):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("scalar_rgb")
    scene = tmp_path / "s.json"
    camera = {"eye": [0, 1, -4], "look_at": [0, 1, 0], "fov": 35, "aperture": 0.2,
              "focus_distance": 3.5}
    scene.write_text(json.dumps({"integrator": "path", "camera": camera,
                                 "spheres": [{"center": [0, 1, 0], "radius": 1,
                                              "material": {"bsdf": {"type": "diffuse"}}}]}))
    sensor = mitsuba_ref.mitsuba_scene(mitsuba_ref.Scene(scene), 4, 32, 32)["sensor"]
    assert (sensor["type"], sensor["fov_axis"], sensor["fov"]) == ("thinlens", "y", 35.0)
    assert (sensor["aperture_radius"], sensor["focus_distance"]) == (0.2, 3.5)
    del camera["focus_distance"]                 # SCENE.md: |look_at - eye| by default
    scene.write_text(json.dumps({"integrator": "path", "camera": camera}))
    sensor = mitsuba_ref.mitsuba_scene(mitsuba_ref.Scene(scene), 4, 32, 32)["sensor"]
    assert sensor["focus_distance"] == 4.0
    camera["aperture"] = 0                       # the pinhole
    scene.write_text(json.dumps({"integrator": "path", "camera": camera}))
    sensor = mitsuba_ref.mitsuba_scene(mitsuba_ref.Scene(scene), 4, 32, 32)["sensor"]
    assert sensor["type"] == "perspective" and "aperture_radius" not in sensor
