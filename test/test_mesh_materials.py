"""Materials from mesh files (docs/SCENE.md "Materials from mesh files", the rule
in docs/RENDERING.md): each triangle keeps the file's material, "material" forces
one, "materials" replaces by name, -v reports what a file brought; files without
materials render as before."""
import base64
import json
import os
import pathlib
import re
import struct
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
MODELS = pathlib.Path("/usr/share/assimp/models")

# Three unit quads side by side at z = 0, seen from +z: the left one "red", the
# middle one a material the MTL does not define (the default material), the
# right one "green". (Assimp 5.2 gives faces before an OBJ's first usemtl the
# material that usemtl names.)
OBJ = """mtllib quads.mtl
v -1.5 -0.5 0
v -0.5 -0.5 0
v -0.5 0.5 0
v -1.5 0.5 0
v -0.5 -0.5 0
v 0.5 -0.5 0
v 0.5 0.5 0
v -0.5 0.5 0
v 0.5 -0.5 0
v 1.5 -0.5 0
v 1.5 0.5 0
v 0.5 0.5 0
usemtl red
f 1 2 3 4
usemtl undefined
f 5 6 7 8
usemtl green
f 9 10 11 12
"""
MTL = """newmtl red
Kd 0.9 0.1 0.1
Ke 1 1 1
newmtl green
Kd 0.1 0.8 0.1
"""
SIZE = (48, 16)  # the quads' centres at pixels 11, 24 and 36 of row 8
CENTRES = (11, 24, 36)


def rtcl(*args):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


def read_ppm(path):
    data = path.read_bytes()
    words, at = [], 0
    while len(words) < 4:  # the header's words, past its comment lines
        while data[at:at + 1].isspace():
            at += 1
        if data[at:at + 1] == b"#":
            at = data.index(b"\n", at) + 1
            continue
        end = at
        while not data[end:end + 1].isspace():
            end += 1
        words.append(data[at:end])
        at = end
    magic, width, height, maximum = words
    pixels = data[at + 1:]
    assert magic == b"P6" and maximum == b"255"
    width, height = int(width), int(height)
    return [[tuple(pixels[3 * (y * width + x):3 * (y * width + x) + 3]) for x in range(width)]
            for y in range(height)]


def scene(tmp_path, mesh, obj=OBJ, mtl=MTL, **extra):
    (tmp_path / "quads.obj").write_text(obj)
    if mtl is not None:
        (tmp_path / "quads.mtl").write_text(mtl)
    doc = {"format": "rtcl-scene", "version": 2,
           "camera": {"eye": [0, 0, 2.4], "look_at": [0, 0, 0], "fov": 30},
           "ambient": [0.1, 0.1, 0.1], "lights": [{"position": [0, 0, 3]}],
           "meshes": [dict({"file": "quads.obj", "smooth": False}, **mesh)]}
    doc.update(extra)
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    return path


def render(tmp_path, path, *options, name="o.ppm"):
    out = tmp_path / name
    result = rtcl(path, "-o", out, "--size", "%dx%d" % SIZE, *options)
    assert result.returncode == 0, result.stderr
    return read_ppm(out), result.stderr


def quad(image, i):
    """The pixel at the middle of quad i (0 left, 1 middle, 2 right)."""
    return image[SIZE[1] // 2][CENTRES[i]]


def test_obj_materials_colour_their_triangles(tmp_path):
    image, _ = render(tmp_path, scene(tmp_path, {}))
    red, plain, green = quad(image, 0), quad(image, 1), quad(image, 2)
    assert red[0] > 200 and red[1] < 110 and red[2] < 110, red
    assert green[1] > 200 and green[0] < 110 and green[2] < 110, green
    assert plain[0] == plain[1] == plain[2] and plain[0] > 150, plain


def test_triangles_without_a_file_material_get_the_default_material(tmp_path):
    """The middle quad (no usemtl) renders as the default material does, bit for bit."""
    kept, _ = render(tmp_path, scene(tmp_path, {}), name="kept.ppm")
    forced, _ = render(tmp_path, scene(tmp_path, {"material": {}}), name="forced.ppm")
    for row_kept, row_forced in zip(kept, forced):
        assert row_kept[19:29] == row_forced[19:29]


@pytest.mark.parametrize("name", ["cube.obj", "quad.ply", "tri.stl", "nodes.gltf"])
def test_files_without_materials_render_as_before(tmp_path, name):
    """No material in the file: the same image as with the default material forced."""
    images = []
    for mesh in ({}, {"material": {}}):
        doc = {"format": "rtcl-scene", "version": 2,
               "camera": {"eye": [3, 4, 9], "look_at": [0, 0, 0]},
               "lights": [{"position": [5, 10, 10]}],
               "meshes": [dict({"file": str(ROOT / "test" / "meshes" / name)}, **mesh)]}
        path = tmp_path / "s.json"
        path.write_text(json.dumps(doc))
        out = tmp_path / "o.ppm"
        result = rtcl(path, "-o", out, "--size", "16x12", "-v")
        assert result.returncode == 0, result.stderr
        images.append(out.read_bytes())
    assert images[0] == images[1]


def test_material_forces_one_on_the_whole_mesh(tmp_path):
    image, err = render(tmp_path, scene(tmp_path, {"material": {"color": [0.1, 0.1, 0.9]}}),
                        "-v")
    for i in range(3):
        assert quad(image, i)[2] > quad(image, i)[0] + 60, quad(image, i)
    assert 'meshes[0] "quads.obj": 2 materials (2 used), 0 textures; replaced by its "material"' in err


def test_materials_replace_the_files_by_name(tmp_path):
    path = scene(tmp_path, {"materials": {"red": "blue", "green": {"color": [1, 1, 0]}}},
                 materials={"blue": {"color": [0.1, 0.1, 0.9]}})
    image, _ = render(tmp_path, path)
    assert quad(image, 0)[2] > quad(image, 0)[0] + 60, quad(image, 0)
    assert quad(image, 2)[0] > 200 and quad(image, 2)[1] > 200 and quad(image, 2)[2] < 110
    plain = quad(image, 1)
    assert plain[0] == plain[1] == plain[2]


def refused(tmp_path, path):
    out = tmp_path / "o.png"
    result = rtcl(path, "-o", out)
    assert result.returncode == 1
    assert not out.exists()
    assert result.stderr.count("\n") == 1, result.stderr
    return result.stderr.rstrip("\n")


def test_an_unknown_file_material_name_lists_the_files(tmp_path):
    path = scene(tmp_path, {"materials": {"gren": {}}})
    assert refused(tmp_path, path) == (
        f'{path}: meshes[0].materials: "quads.obj" has no material "gren"; its materials '
        'are "red", "green", "undefined"; did you mean "green"?')


def test_material_and_materials_exclude_each_other(tmp_path):
    path = scene(tmp_path, {"material": {}, "materials": {"red": {}}})
    assert refused(tmp_path, path) == (
        f'{path}: meshes[0]: "material" (one for the whole mesh) and "materials" (by the '
        "file's names) exclude each other")


def test_materials_must_be_an_object(tmp_path):
    path = scene(tmp_path, {"materials": ["red"]})
    assert refused(tmp_path, path) == f"{path}: meshes[0].materials: must be an object, got an array"


def test_an_unknown_scene_material_in_materials_is_named(tmp_path):
    path = scene(tmp_path, {"materials": {"red": "glas"}}, materials={"glass": {}})
    assert refused(tmp_path, path) == (
        f'{path}: meshes[0].materials.red: unknown material "glas"; did you mean "glass"?')


def test_a_material_number_that_is_not_finite_is_refused(tmp_path):
    path = scene(tmp_path, {}, mtl=MTL.replace("Kd 0.9 0.1 0.1", "Kd 1e400 0.1 0.1"))
    assert refused(tmp_path, path) == (
        f'{path}: meshes[0]: "quads.obj": material "red": Kd is not finite')


def test_verbose_reports_materials_textures_and_what_was_not_understood(tmp_path):
    _, err = render(tmp_path, scene(tmp_path, {"missing_textures": "warn"},
                                    mtl=MTL + "map_Kd brick.png\nmap_bump b.png\n"), "-v")
    assert ('rtcl: meshes[0] "quads.obj": 2 materials (2 used), 1 texture; '
            "not understood: emissive, Height texture") in err, err
    assert ('rtcl: warning: %s: meshes[0].file: "quads.obj": material "green": cannot read '
            'texture "brick.png": No such file or directory; its material renders without it'
            % (tmp_path / "s.json")) in err, err


def gltf(materials, primitives):
    """A glTF of one quad per primitive, side by side (as OBJ above), each with the
    material of its primitive."""
    quads = [[(-1.5 + i, -0.5, 0), (-0.5 + i, -0.5, 0), (-0.5 + i, 0.5, 0), (-1.5 + i, 0.5, 0)]
             for i in range(3)]
    blob = b"".join(struct.pack("<12f", *[c for v in q for c in v]) for q in quads)
    index_at = len(blob)
    blob += struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    views = [{"buffer": 0, "byteOffset": 48 * i, "byteLength": 48} for i in range(3)]
    views.append({"buffer": 0, "byteOffset": index_at, "byteLength": 12})
    accessors = [{"bufferView": i, "componentType": 5126, "count": 4, "type": "VEC3",
                  "min": [-1.5 + i, -0.5, 0], "max": [-0.5 + i, 0.5, 0]} for i in range(3)]
    accessors.append({"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"})
    prims = []
    for i, material in enumerate(primitives):
        prim = {"attributes": {"POSITION": i}, "indices": 3}
        if material is not None:
            prim["material"] = material
        prims.append(prim)
    return {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}], "meshes": [{"primitives": prims}],
            "materials": materials,
            "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                         + base64.b64encode(blob).decode()}],
            "bufferViews": views, "accessors": accessors}


def gltf_scene(tmp_path, doc, mesh=None):
    (tmp_path / "m.gltf").write_text(json.dumps(doc))
    return scene(tmp_path, dict({"file": "m.gltf"}, **(mesh or {})))


def test_gltf_base_colour_metallic_and_roughness(tmp_path):
    """A rough red dielectric is red; a smooth metal mirrors the background (kd 0, kr 1);
    a primitive without a material gets the default material."""
    doc = gltf([{"name": "red", "pbrMetallicRoughness": {
                    "baseColorFactor": [0.9, 0.1, 0.1, 1], "metallicFactor": 0,
                    "roughnessFactor": 1}},
                {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
                                          "metallicFactor": 1, "roughnessFactor": 0}}],
               [0, None, 1])
    image, err = render(tmp_path, gltf_scene(tmp_path, doc), "-v")
    red, plain, mirror = quad(image, 0), quad(image, 1), quad(image, 2)
    assert red[0] > 200 and red[1] < 110 and red[2] < 110, red
    assert plain[0] == plain[1] == plain[2] and plain[0] > 150, plain
    # the background (black) mirrored, plus the light's highlight off a metal of ks 1
    assert 'meshes[0] "m.gltf": 2 materials (2 used), 0 textures' in err
    forced, _ = render(tmp_path, gltf_scene(tmp_path, doc, {"materials": {"#1": {
        "color": [0.5, 0.5, 0.5], "diffuse": 0, "ambient": 0, "specular": 1,
        "shininess": 19998, "reflect": 1}}}), name="forced.ppm")
    assert forced == image  # the rule, by hand: kd = ka = 0, ks = kr = 1, 2/1e-4 - 2


def test_gltf_transmission_and_blend_see_through(tmp_path):
    """KHR_materials_transmission and alphaMode BLEND let the plane behind show (in the
    shadow of the quads, which transparent objects cast too: its ambient blue)."""
    doc = gltf([{"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0,
                                                           "roughnessFactor": 1},
                 "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                                "KHR_materials_ior": {"ior": 1.0}}},
                {"name": "veil", "alphaMode": "BLEND", "pbrMetallicRoughness": {
                    "baseColorFactor": [1, 1, 1, 0], "metallicFactor": 0}}],
               [0, 1, 0])
    doc["extensionsUsed"] = ["KHR_materials_transmission", "KHR_materials_ior"]
    floor = [{"point": [0, 0, -1], "normal": [0, 0, 1], "material": {"color": [0, 0, 1]}}]
    (tmp_path / "m.gltf").write_text(json.dumps(doc))
    image, _ = render(tmp_path, scene(tmp_path, {"file": "m.gltf"}, planes=floor))
    for i in range(3):
        pixel = quad(image, i)
        assert pixel[2] > 60 and pixel[0] < 30 and pixel[1] < 30, (i, pixel)


KERNELS = ["serial", "naive", "cyclic", "dynamic", "persistent", "wavefront"]


# File materials reach the kernels through the triangle's material word, as
# the scene's own materials do: make test compares the stack walk's kernels
# and the wavefront, make test-long every kernel.
@pytest.mark.parametrize("kernels", [
    pytest.param(["serial", "dynamic", "wavefront"], id="walk-and-wavefront"),
    pytest.param(KERNELS, id="every-kernel", marks=pytest.mark.slow)])
def test_kernels_agree_on_file_materials_and_with_the_reference(tmp_path, kernels):
    path = scene(tmp_path, {})
    images = {k: render(tmp_path, path, "-k", k, "--size", "24x8", name=k + ".ppm")[0]
              for k in kernels + ["reference"]}
    for k in kernels[1:]:
        assert images[k] == images[kernels[0]], k
    worst = max(abs(a - b) for ra, rb in zip(images["reference"], images["dynamic"])
                for pa, pb in zip(ra, rb) for a, b in zip(pa, pb))
    assert worst <= 2


@pytest.mark.skipif(not (MODELS / "glTF2" / "2CylinderEngine-glTF-Binary").is_dir(),
                    reason="Debian's assimp-testmodels is not installed")
def test_the_engine_keeps_its_parts_colours(tmp_path):
    engine = MODELS / "glTF2" / "2CylinderEngine-glTF-Binary" / "2CylinderEngine.glb"
    doc = {"format": "rtcl-scene", "version": 2,
           "camera": {"eye": [0, 300, 600], "look_at": [0, 0, 0]},
           "lights": [{"position": [0, 1000, 1000]}],
           "meshes": [{"file": str(engine)}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    out = tmp_path / "o.ppm"
    result = rtcl(path, "-o", out, "--size", "32x24", "-v")
    assert result.returncode == 0, result.stderr
    assert "2CylinderEngine.glb\": 34 materials (34 used), 0 textures" in result.stderr
    colours = {p for row in read_ppm(out) for p in row}
    assert any(b > 2 * r + 20 and b > 2 * g + 20 for r, g, b in colours)  # the blue parts


FUZZ_SEEDS = ROOT / "test" / "fuzz_mesh_materials"


@pytest.mark.parametrize("seed", sorted(p.name for p in FUZZ_SEEDS.iterdir()
                                        if p.suffix in (".obj", ".gltf")))
def test_broken_material_references_are_one_message_or_a_picture(tmp_path, seed):
    """The mesh fuzzer's seeds for materials (test/fuzz_mesh_materials/README.md):
    missing, huge, malformed, out of range, textures outside the folder. Each is
    rendered or refused with one message, and then nothing is written."""
    doc = {"format": "rtcl-scene", "version": 2,
           "camera": {"eye": [0.3, 0.3, 3], "look_at": [0.3, 0.3, 0]},
           "meshes": [{"file": str(FUZZ_SEEDS / seed)}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    out = tmp_path / "o.ppm"
    result = rtcl(path, "-o", out, "--size", "8x8", "-q")
    expected = FUZZ_SEEDS.joinpath("README.md").read_text()
    if result.returncode == 0:
        assert out.exists() and re.search(rf"- `{re.escape(seed)}`[^:]*: rendered", expected)
    else:
        assert result.returncode == 1 and not out.exists()
        assert result.stderr.count("\n") == 1 and result.stderr.startswith(f"{path}: meshes[0]")
        assert re.search(rf"- `{re.escape(seed)}`[^:]*: refused", expected)


CLEARCOAT = MODELS / "glTF2" / "ClearCoat-glTF" / "ClearCoatTest.gltf"


@pytest.mark.skipif(not CLEARCOAT.is_file(), reason="Debian's assimp-testmodels is not installed")
def test_a_textured_gltf_keeps_its_materials_and_its_texture(tmp_path):
    """Issue 27's textured glTF of several materials from assimp-testmodels:
    its 19 materials and its base-colour texture reach the device (-v), and
    its red and blue spheres render red and blue."""
    doc = {"format": "rtcl-scene", "version": 2,
           "camera": {"eye": [-2.1, 0.3, 22], "look_at": [-2.1, 0.3, 0.5]},
           "lights": [{"position": [5, 5, 20]}],
           "meshes": [{"file": str(CLEARCOAT)}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    out = tmp_path / "o.ppm"
    result = rtcl(path, "-o", out, "--size", "40x50", "-v")
    assert result.returncode == 0, result.stderr
    # its base colour texture, and for the path integrator its
    # metallic-roughness (linear), emissive and normal textures (issue 40)
    assert 'ClearCoatTest.gltf": 19 materials (19 used), 11 textures' in result.stderr
    assert 'texture "PartialCoating_Alpha.png": 256x256 8-bit sRGB' in result.stderr
    assert 'texture "RoughnessStripes.png": 512x512 8-bit linear' in result.stderr
    colours = {p for row in read_ppm(out) for p in row}
    assert any(r > g + 80 and r > b + 80 for r, g, b in colours)  # the red row
    assert any(b > r + 30 and b > g + 30 for r, g, b in colours)  # the blue rows
