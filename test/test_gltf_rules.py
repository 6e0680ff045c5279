"""What the glTF 2.0 specification asks of a file, and rtcl now checks or reads
(issue 39 findings 6, 7, 10, 16; docs/SCENE.md): an index naming a vertex its
primitive lacks and an extension in extensionsRequired that rtcl does not read are
errors; JSON that does not parse says where; a perspective camera of yfov 0 is
not called orthographic; a mesh entry's "camera": null is refused; a camera is
placed by the node that holds it, whatever the other nodes are called; a base
colour texture's KHR_texture_transform and texCoord are applied, and so are an
MTL's map_Kd -s and -o; a data: image that is not base64 says so."""
import base64
import json
import math
import pathlib
import struct

import pytest

from test_textures import (TEXELS, expected, gltf_quad, pixel_uv, quad_scene, read_pfm,
                           render, rtcl)


def triangle_gltf(indices=(0, 1, 2, 0, 2, 3), extra=None):
    """A glTF of one quad (two triangles) at z = 0, its indices as given."""
    pos = struct.pack("<12f", -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0)
    idx = struct.pack(f"<{len(indices)}H", *indices)
    idx += b"\0" * (-len(idx) % 4)
    buf = pos + idx
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64,"
                        + base64.b64encode(buf).decode()}],
           "bufferViews": [{"buffer": 0, "byteLength": 48},
                           {"buffer": 0, "byteOffset": 48, "byteLength": 2 * len(indices)}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [-1, -1, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5123, "count": len(indices),
                          "type": "SCALAR"}]}
    doc.update(extra or {})
    return doc


def scene_of(tmp_path, gltf_text, mesh=None, camera=True):
    (tmp_path / "m.gltf").write_text(gltf_text)
    doc = {"format": "rtcl-scene", "version": 2, "lights": [{"position": [0, 0, 5]}],
           "meshes": [dict({"file": "m.gltf"}, **(mesh or {}))]}
    if camera:
        doc["camera"] = {"eye": [0, 0, 5], "look_at": [0, 0, 0]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    return path


def refused(path):
    out = path.parent / "o.ppm"
    result = rtcl(path, "-o", out, "--size", "8x8")
    assert result.returncode != 0 and not out.exists(), result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0].replace(f"{path.parent}/", "")


def test_an_index_naming_a_missing_vertex_is_an_error(tmp_path):
    """Vertex 999 of 4: Assimp 5.2 dropped the triangle and rendered the other."""
    path = scene_of(tmp_path, json.dumps(triangle_gltf((0, 1, 2, 0, 2, 999))))
    assert refused(path) == (
        's.json: meshes[0].file: cannot read "m.gltf": a triangle of it names a vertex its '
        "primitive does not have (glTF: every index must be less than the POSITION "
        "accessor's count)")


@pytest.mark.parametrize("name", ["EXT_not_a_real_one", "KHR_materials_pbrSpecularGlossiness",
                                  "EXT_meshopt_compression", "KHR_technique_webgl"])
def test_a_required_extension_rtcl_does_not_read_is_an_error_naming_it(tmp_path, name):
    doc = triangle_gltf(extra={"extensionsUsed": [name], "extensionsRequired": [name]})
    assert refused(scene_of(tmp_path, json.dumps(doc))) == (
        f's.json: meshes[0].file: cannot read "m.gltf": it requires the glTF extension "{name}"'
        " (extensionsRequired), which rtcl does not read")


def test_required_extensions_rtcl_reads_are_accepted(tmp_path):
    """Draco too: the importer decodes it (Debian's Assimp is built with it)."""
    names = ["KHR_texture_transform", "KHR_materials_ior", "KHR_materials_transmission",
             "KHR_lights_punctual", "KHR_draco_mesh_compression"]
    doc = triangle_gltf(extra={"extensionsUsed": names, "extensionsRequired": names})
    result = rtcl(scene_of(tmp_path, json.dumps(doc)), "-o", tmp_path / "o.ppm",
                  "--size", "8x8")
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("text, words", [
    ('{"asset": {"version": "2.0"},, }', "line 1, column 30: string or '}' expected near ','"),
    ('{"asset": {"version": "2.0"}, "scale": 1e999}',
     "line 1, column 44: real number overflow near '1e999'"),
])
def test_json_that_does_not_parse_says_where(tmp_path, text, words):
    """Before: "No suitable reader found for the file format of file "m.gltf"."""
    assert refused(scene_of(tmp_path, text)) == (
        f's.json: meshes[0].file: cannot read "m.gltf": its glTF JSON does not parse: {words}')


def camera_gltf(nodes, cameras):
    doc = triangle_gltf()
    doc["nodes"] = [{"mesh": 0}] + nodes
    doc["scenes"] = [{"nodes": list(range(len(nodes) + 1))}]
    doc["cameras"] = cameras
    return json.dumps(doc)


PERSPECTIVE = {"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}


def test_a_perspective_camera_of_yfov_0_is_not_called_orthographic(tmp_path):
    text = camera_gltf([{"name": "Cam", "camera": 0, "translation": [0, 0, 5]}],
                       [{"type": "perspective", "perspective": {"yfov": 0, "znear": 0.1}}])
    assert refused(scene_of(tmp_path, text, {"camera": "Cam"}, camera=False)) == (
        's.json: meshes[0].camera: "m.gltf": camera "Cam": its vertical field of view is 0 '
        "degrees; rtcl needs 0 < fov < 180")


@pytest.mark.parametrize("camera", [True, False])
def test_camera_null_is_refused_not_taken_for_true(tmp_path, camera):
    text = camera_gltf([{"name": "Cam", "camera": 0, "translation": [0, 0, 5]}], [PERSPECTIVE])
    assert refused(scene_of(tmp_path, text, {"camera": None}, camera=camera)) == (
        "s.json: meshes[0].camera: must be true, false or the name of a camera of the file,"
        " got null")


def test_a_camera_is_placed_by_the_node_that_holds_it_not_the_first_of_its_name(tmp_path):
    """Node 1 "Cam" (no camera) at y = 100; node 2, also "Cam", holds the camera."""
    text = camera_gltf([{"name": "Cam", "translation": [0, 100, 0]},
                        {"name": "Cam", "camera": 0, "translation": [0, 1, 5]}], [PERSPECTIVE])
    path = scene_of(tmp_path, text, {"camera": True}, camera=False)
    result = rtcl(path, "-o", tmp_path / "o.ppm", "--size", "8x8", "-v")
    assert result.returncode == 0, result.stderr
    assert ('rtcl: meshes[0] "m.gltf": camera "Cam": eye [0, 1, 5], look_at [0, 1, 4], '
            "up [0, 1, 0], fov 40.10704565915762") in result.stderr


def textured_quad(tmp_path, binding, texcoords=None):
    """test_textures' glTF quad (coordinates 0 ... 1) with its base colour
    texture's binding, and (texcoords) a TEXCOORD_1 of these coordinates and a
    TEXCOORD_0 of zeros instead."""
    path = quad_scene(tmp_path)
    doc = json.loads(path.read_text())
    name = gltf_quad(tmp_path, {"wrapS": 10497, "wrapT": 10497}, lo=0.0, hi=1.0)
    gltf = json.loads((tmp_path / name).read_text())
    gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"].update(binding)
    gltf["materials"][0]["name"] = "tiles"  # KHR_texture_transform's texCoord goes by it
    gltf["extensionsUsed"] = ["KHR_texture_transform"]
    if texcoords:
        blob = base64.b64decode(gltf["buffers"][0]["uri"].split(",")[1])
        zeros = b"\0" * 32
        blob += zeros
        gltf["buffers"][0] = {"byteLength": len(blob), "uri": "data:application/octet-stream;"
                              "base64," + base64.b64encode(blob).decode()}
        gltf["bufferViews"].append({"buffer": 0, "byteOffset": len(blob) - 32, "byteLength": 32})
        gltf["accessors"].append({"bufferView": 3, "componentType": 5126, "count": 4,
                                  "type": "VEC2"})
        attributes = gltf["meshes"][0]["primitives"][0]["attributes"]
        attributes["TEXCOORD_1"], attributes["TEXCOORD_0"] = 1, 3
    (tmp_path / name).write_text(json.dumps(gltf))
    doc["meshes"][0]["file"] = name
    doc["ambient"] = [1 / 0.96] * 3  # metallic 0: kd = 0.96 (test_textures' wrap test)
    path.write_text(json.dumps(doc))
    return read_pfm(render(path)[0])


def check_lookups(image, transform):
    """Each pixel's colour is the texture at its coordinates (glTF's: v down)
    through transform, then back to RENDERING.md's v up."""
    for x, y in ((2, 2), (5, 30), (17, 17), (30, 6), (33, 33), (11, 26), (24, 9)):
        u, v_up = pixel_uv(x, y)
        u2, v2 = transform(u, 1 - v_up)
        want = [c / 0.96 for c in expected(TEXELS, u2, 1 - v2)[:3]]
        assert all(abs(g - w) < 3e-4 for g, w in zip(image[y][x], want)), \
            (x, y, image[y][x], want)


def test_khr_texture_transform_offset_rotation_and_scale(tmp_path):
    offset, rotation, scale = (0.25, -0.5), 0.4, (2.0, 1.5)
    image = textured_quad(tmp_path, {"extensions": {"KHR_texture_transform": {
        "offset": list(offset), "rotation": rotation, "scale": list(scale)}}})
    c, s = math.cos(rotation), math.sin(rotation)
    check_lookups(image, lambda u, v: (c * scale[0] * u + s * scale[1] * v + offset[0],
                                       -s * scale[0] * u + c * scale[1] * v + offset[1]))


@pytest.mark.parametrize("binding", [
    {"texCoord": 1},
    {"extensions": {"KHR_texture_transform": {"texCoord": 1}}},
])
def test_tex_coord_picks_the_set_of_coordinates(tmp_path, binding):
    image = textured_quad(tmp_path, binding, texcoords=True)
    check_lookups(image, lambda u, v: (u, v))


def test_a_data_uri_that_is_not_base64_says_so(tmp_path):
    """Before: cannot read texture "": it is not a regular file (the model's folder)."""
    path = quad_scene(tmp_path)
    doc = json.loads(path.read_text())
    name = gltf_quad(tmp_path, {"wrapS": 10497, "wrapT": 10497})
    gltf = json.loads((tmp_path / name).read_text())
    gltf["images"][0]["uri"] = "data:image/png,not-base64"
    (tmp_path / name).write_text(json.dumps(gltf))
    doc["meshes"][0]["file"] = name
    path.write_text(json.dumps(doc))
    assert refused(path) == (
        's.json: meshes[0].file: "q.gltf": material "#0": cannot read texture "": images[0] is'
        " a data: URI that is not base64; rtcl reads only base64 data: URIs")


def obj_quad(tmp_path, map_kd, extra_mtl=""):
    path = quad_scene(tmp_path)
    mtl = (tmp_path / "q.mtl").read_text().replace("map_Kd t.png", f"map_Kd {map_kd}")
    (tmp_path / "q.mtl").write_text(mtl + extra_mtl)
    return path


def test_mtl_map_kd_scale_and_offset(tmp_path):
    """u' = s u + o in the OBJ's coordinates (v up), as three.js and Blender read
    -s and -o; before, Assimp passed over them and the texture lay untransformed."""
    path = obj_quad(tmp_path, "-s 2 1.5 1 -o 0.25 -0.5 0 -clamp off t.png")
    image = read_pfm(render(path)[0])
    for x, y in ((2, 2), (5, 30), (17, 17), (30, 6), (33, 33), (11, 26), (24, 9)):
        u, v = pixel_uv(x, y)
        want = expected(TEXELS, 2 * u + 0.25, 1.5 * v - 0.5)[:3]
        assert all(abs(g - w) < 3e-4 for g, w in zip(image[y][x], want)), \
            (x, y, image[y][x], want)


def test_a_map_d_transformed_unlike_map_kd_is_named_not_understood(tmp_path):
    path = obj_quad(tmp_path, "-o 0.5 0 0 t.png", "map_d -s 2 2 1 t.png\n")
    _, err = render(path, "-v")
    assert "not understood: map_d -s/-o unlike map_Kd's" in err, err


SAMPLE = pathlib.Path("/usr/share/assimp/models/glTF2/textureTransform/TextureTransformTest.gltf")


@pytest.mark.skipif(not SAMPLE.exists(), reason="assimp-testmodels is not installed")
def test_khronos_texture_transform_sample_arrows_point_at_the_green_markers(tmp_path):
    """Khronos' TextureTransformTest (in assimp-testmodels): on the bottom row the
    arrow texture, rotated, scaled, and both with an offset, must point at the green
    marker of each quad; a rotation the wrong way round points at the red one. An
    arrow's tip is the dark texels beside its marker."""
    doc = {"format": "rtcl-scene", "version": 2, "image": {"width": 480, "height": 320},
           "camera": {"eye": [0, 0, 4.2], "look_at": [0, 0, 0], "fov": 50},
           "ambient": [1, 1, 1], "background": [0.2, 0.2, 0.2], "lights": [],
           "meshes": [{"file": str(SAMPLE), "smooth": False}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    out = tmp_path / "o.ppm"
    result = rtcl(path, "-o", out)
    assert result.returncode == 0, result.stderr
    data = out.read_bytes()[-480 * 320 * 3:]
    pixel = lambda x, y: data[3 * (480 * y + x):3 * (480 * y + x) + 3]  # noqa: E731

    def centre(x0, x1, test):
        """The centre of the pixels passing test in columns x0 ... x1 of the bottom row."""
        found = [(x, y) for y in range(160, 270) for x in range(x0, x1) if test(pixel(x, y))]
        assert found
        return (sum(p[0] for p in found) // len(found), sum(p[1] for p in found) // len(found))

    def dark_near(point, r=14):
        return sum(max(pixel(x, y)) < 60 for y in range(point[1] - r, point[1] + r)
                   for x in range(point[0] - r, point[0] + r))
    green = lambda c: c[1] > 150 and c[0] < 100 and c[2] < 100  # noqa: E731
    red = lambda c: c[0] > 150 and c[1] < 80 and c[2] < 80  # noqa: E731
    for x0, x1 in ((100, 200), (200, 285), (285, 380)):  # rotation, scale, all
        assert dark_near(centre(x0, x1, green)) > 0, (x0, x1)
    assert dark_near(centre(100, 200, red)) == 0


def test_a_control_byte_in_a_camera_name_is_shown_escaped(tmp_path):
    """GUIDE.md: a name read from a file shows its control bytes as \\x1b, in the list
    of cameras and in -v. Before: "Ca?m"; the exact name was not found."""
    text = camera_gltf([{"name": "Ca\x1bm", "camera": 0, "translation": [0, 0, 5]}],
                       [PERSPECTIVE])
    assert refused(scene_of(tmp_path, text, {"camera": "Cam"}, camera=False)) == (
        's.json: meshes[0].camera: "m.gltf" has no camera "Cam"; its cameras are "Ca\\x1bm"')
    path = scene_of(tmp_path, text, {"camera": "Ca\x1bm"}, camera=False)
    result = rtcl(path, "-o", tmp_path / "o.ppm", "--size", "8x8", "-v")
    assert result.returncode == 0, result.stderr
    assert 'rtcl: meshes[0] "m.gltf": camera "Ca\\x1bm": eye [0, 0, 5]' in result.stderr
    assert "\x1b" not in result.stderr
