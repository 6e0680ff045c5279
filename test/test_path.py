"""The path integrator end to end (issue 40; SCENE.md "Path tracing",
RENDERING.md "Path tracing"): every single-pass kernel gives the same
path-traced image; white furnaces render what the physics says; the new
fields' and option's messages; the kernels that cannot trace paths yet refuse
them rather than render Whitted's image."""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import builds

ROOT = Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
BOX = ROOT / "test" / "scenes" / "path_box.json"


def rtcl(*args):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True, cwd=ROOT,
                          timeout=300)


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(height, width, 3)[::-1]


def render(scene, tmp_path, name, *args):
    out = tmp_path / f"{name}.pfm"
    result = rtcl(scene, "-o", out, "-q", *args)
    assert result.returncode == 0, result.stderr
    return out


def write_scene(tmp_path, doc, name="s.json"):
    path = tmp_path / name
    path.write_text(json.dumps(doc))
    return path


def same_image_from_kernels(tmp_path, kernels):
    images = {k: render(BOX, tmp_path, k, "-k", k, "--size", "20x20", "--spp", "4")
              for k in kernels}
    first = images[kernels[0]].read_bytes()
    assert read_pfm(images[kernels[0]]).mean() > 0.05  # lit, not black
    for kernel, path in images.items():
        assert path.read_bytes() == first, f"{kernel} differs from {kernels[0]}"


def test_dynamic_and_wavefront_give_the_same_image(tmp_path):
    same_image_from_kernels(tmp_path, ["dynamic", "wavefront"])


@pytest.mark.slow
def test_every_kernel_gives_the_same_image(tmp_path):
    same_image_from_kernels(tmp_path, ["serial", "naive", "cyclic", "dynamic", "persistent",
                                       "wavefront"])


def furnace(tmp_path, bsdf, samples=64, size="16x16"):
    """A sphere filling the middle of the image under a uniform environment
    of radiance 1: the mean of the pixels it covers."""
    doc = {"format": "rtcl-scene", "version": 1, "integrator": "path", "max_depth": 64,
           "image": {"width": 16, "height": 16},
           "camera": {"eye": [0, 0, -4], "look_at": [0, 0, 0], "fov": 12},
           "background": [1, 1, 1],
           "spheres": [{"center": [0, 0, 0], "radius": 1, "material": {"bsdf": bsdf}}]}
    image = read_pfm(render(write_scene(tmp_path, doc), tmp_path, "furnace", "--size", size,
                            "--spp", samples))
    return image.mean(axis=(0, 1))


@pytest.mark.parametrize("rho", [0.3, 0.8])
def test_white_furnace_diffuse_renders_its_albedo(tmp_path, rho):
    mean = furnace(tmp_path, {"type": "diffuse", "reflectance": [rho] * 3})
    assert np.allclose(mean, rho, rtol=0.01), mean


def test_white_furnace_smooth_glass_is_invisible(tmp_path):
    # A smooth dielectric loses no energy: radiance 1 all round stays 1.
    mean = furnace(tmp_path, {"type": "dielectric", "ior": 1.5})
    assert np.allclose(mean, 1.0, rtol=0.01), mean


@pytest.mark.slow
def test_white_furnace_principled_stays_below_one(tmp_path):
    mean = furnace(tmp_path, {"type": "principled", "base_color": [1, 1, 1], "roughness": 0.4})
    assert (mean <= 1.01).all() and (mean > 0.8).all(), mean


def test_white_furnace_rough_conductor_loses_a_little(tmp_path):
    # Single-scattering GGX loses energy at higher roughness, never gains.
    mean = furnace(tmp_path, {"type": "conductor", "reflectance": [1, 1, 1], "roughness": 0.5})
    assert (mean <= 1.005).all() and (mean > 0.85).all(), mean


def test_whitted_scene_ignores_the_path_fields(tmp_path):
    # bsdf and emission are read and checked but change nothing under Whitted.
    with open(ROOT / "scenes" / "two_balls.json") as f:
        doc = json.load(f)
    plain = render(write_scene(tmp_path, doc, "a.json"), tmp_path, "a", "--size", "24x16")
    for sphere in doc["spheres"]:
        if isinstance(sphere.get("material"), dict):
            sphere["material"]["emission"] = [5, 5, 5]
            sphere["material"]["bsdf"] = {"type": "diffuse"}
    marked = render(write_scene(tmp_path, doc, "b.json"), tmp_path, "b", "--size", "24x16")
    assert plain.read_bytes() == marked.read_bytes()


def test_integrator_option_overrides_the_scene(tmp_path):
    path = render(BOX, tmp_path, "p", "--size", "12x12")
    with open(BOX) as f:
        doc = json.load(f)
    del doc["integrator"]
    scene = write_scene(tmp_path, doc)
    again = render(scene, tmp_path, "again", "--integrator", "path", "--size", "12x12")
    assert again.read_bytes() == path.read_bytes()


@pytest.mark.slow
def test_integrator_option_whitted_overrides_a_path_scene(tmp_path):
    whitted = render(BOX, tmp_path, "w", "--integrator", "whitted", "--size", "12x12")
    path = render(BOX, tmp_path, "p", "--size", "12x12")
    assert whitted.read_bytes() != path.read_bytes()


def failure(result, message, status=None):
    assert result.returncode != 0, result.stderr
    if status is not None:
        assert result.returncode == status
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert message in lines[0], lines[0]


def box_with(tmp_path, change):
    with open(BOX) as f:
        doc = json.load(f)
    change(doc)
    return write_scene(tmp_path, doc)


@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(integrator="paths"),
     'integrator: must be "whitted" or "path", got "paths"; did you mean "path"?'),
    (lambda d: d.update(integrator=1), 'integrator: must be "whitted" or "path", got an integer'),
    (lambda d: d["materials"]["gold"]["bsdf"].update(type="condutor"),
     'materials.gold.bsdf.type: must be "diffuse", "conductor", "dielectric" or "principled", '
     'got "condutor"; did you mean "conductor"?'),
    (lambda d: d["materials"]["gold"]["bsdf"].pop("type"),
     "materials.gold.bsdf.type: required field is missing"),
    (lambda d: d["materials"]["gold"]["bsdf"].update(ior=1.5),
     'materials.gold.bsdf: unknown key "ior"'),
    (lambda d: d["materials"]["gold"]["bsdf"].update(roughnes=0.2),
     'materials.gold.bsdf: unknown key "roughnes"; did you mean "roughness"?'),
    (lambda d: d["materials"]["gold"]["bsdf"].update(roughness=1.5),
     "materials.gold.bsdf.roughness: must be between 0 and 1, got 1.5"),
    (lambda d: d["materials"]["gold"]["bsdf"].update(reflectance=[1.2, 0.8, 0.3]),
     "materials.gold.bsdf.reflectance: must be a color with parts between 0 and 1, got "
     "[1.2, 0.8, 0.3]"),
    (lambda d: d["materials"]["gold"].update(bsdf="gold"),
     "materials.gold.bsdf: must be an object, got a string"),
    (lambda d: d["materials"]["lamp"].update(emission=[-1, 0, 0]),
     "materials.lamp.emission"),
    (lambda d: d["materials"]["lamp"].update(emision=[1, 0, 0]),
     'materials.lamp: unknown key "emision"; did you mean "emission"?'),
    (lambda d: d.update(environment={"scale": 2}), 'environment: needs "file"'),
    (lambda d: d.update(environment={"file": 3}), 'environment.file: must be a file name, got an integer'),
    (lambda d: d.update(environment={"file": ""}), 'environment.file: must be a file name, got ""'),
    (lambda d: d.update(environment={"file": "sky.hdr", "scale": -1}),
     "environment.scale: must be >= 0, got -1"),
    (lambda d: d.update(environment={"file": "nothere.hdr", "rotat": 2}),
     'environment: unknown key "rotat"; did you mean "rotate"?'),
])
def test_scene_errors(tmp_path, change, message):
    failure(rtcl(box_with(tmp_path, change), "-o", tmp_path / "x.pfm"), message)
    assert not (tmp_path / "x.pfm").exists()


def test_integrator_option_error(tmp_path):
    failure(rtcl(BOX, "--integrator", "pth", "-o", tmp_path / "x.pfm"),
            'rtcl: --integrator: expected whitted or path, got "pth"', 2)


@pytest.mark.slow
def test_counts_agree_between_kernels(tmp_path):
    """The flop count, rays and the work map of a path-traced render are the
    same whichever kernel traces it (the wavefront's bounces included)."""
    stats = {}
    for kernel in ["dynamic", "wavefront"]:
        out = tmp_path / f"{kernel}.json"
        result = rtcl(BOX, "-k", kernel, "--size", "12x12", "--spp", "3", "-o",
                      tmp_path / f"{kernel}.pfm", "-q", "--stats", out, "--work-map",
                      tmp_path / f"{kernel}.npy")
        assert result.returncode == 0, result.stderr
        stats[kernel] = json.loads(out.read_text())
        assert stats[kernel]["total_flops"] > 0
    assert stats["dynamic"]["total_flops"] == stats["wavefront"]["total_flops"]
    assert stats["dynamic"]["rays"] == stats["wavefront"]["rays"]
    assert (np.load(tmp_path / "dynamic.npy") == np.load(tmp_path / "wavefront.npy")).all()


def test_ambient_is_warned_about_under_path(tmp_path):
    scene = box_with(tmp_path, lambda d: d.update(ambient=[0.2, 0.2, 0.2]))
    result = rtcl(scene, "-o", tmp_path / "x.pfm", "-q", "--size", "8x8", "--spp", "2")
    assert result.returncode == 0, result.stderr
    assert result.stderr.splitlines() == [
        f"rtcl: warning: {scene}: ambient: has no meaning under the path integrator "
        "(indirect light is traced); it is ignored"]


def test_environment_is_warned_about_under_whitted(tmp_path):
    write_hdr(tmp_path / "sky.hdr", [[(1.0, 1.0, 1.0)] * 8] * 2)
    scene = box_with(tmp_path, lambda d: d.update(environment={"file": "sky.hdr"}))
    result = rtcl(scene, "--integrator", "whitted", "-o", tmp_path / "x.pfm", "-q", "--size",
                  "8x8")
    assert result.returncode == 0, result.stderr
    assert result.stderr.splitlines() == [
        f"rtcl: warning: {scene}: environment: is used only by the path integrator; it is "
        "ignored"]


def test_model_emission_is_rendered_under_path(tmp_path):
    """glTF emissiveFactor times KHR_materials_emissive_strength (read by
    rtcl-meshread from the file: Assimp 5.2 does not), and MTL Ke, are the
    materials' emission: with no other light, a black emitting quad facing
    the camera shows its radiance; one without stays black."""
    import base64
    import struct
    quads = [[(-1.5 + i, -0.5, 0), (-0.5 + i, -0.5, 0), (-0.5 + i, 0.5, 0), (-1.5 + i, 0.5, 0)]
             for i in range(2)]
    blob = b"".join(struct.pack("<12f", *[c for v in q for c in v]) for q in quads)
    blob += struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    black = {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 1}
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": i}, "indices": 2,
                                       "material": i} for i in range(2)]}],
           "materials": [{"pbrMetallicRoughness": black, "emissiveFactor": [1, 0.5, 0.25],
                          "extensions": {"KHR_materials_emissive_strength":
                                         {"emissiveStrength": 2}}},
                         {"pbrMetallicRoughness": black}],
           "extensionsUsed": ["KHR_materials_emissive_strength"],
           "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                        + base64.b64encode(blob).decode()}],
           "bufferViews": [{"buffer": 0, "byteOffset": 48 * i, "byteLength": 48}
                           for i in range(2)] + [{"buffer": 0, "byteOffset": 96,
                                                   "byteLength": 12}],
           "accessors": [{"bufferView": i, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [-1.5 + i, -0.5, 0], "max": [-0.5 + i, 0.5, 0]}
                         for i in range(2)] + [{"bufferView": 2, "componentType": 5123,
                                                "count": 6, "type": "SCALAR"}]}
    (tmp_path / "m.gltf").write_text(json.dumps(doc))
    (tmp_path / "q.obj").write_text("mtllib q.mtl\nv 0.6 -0.5 0\nv 1.6 -0.5 0\nv 1.6 0.5 0\n"
                                    "v 0.6 0.5 0\nusemtl glow\nf 1 2 3 4\n")
    (tmp_path / "q.mtl").write_text("newmtl glow\nKd 0 0 0\nKe 0.25 0.5 1\n")
    scene = write_scene(tmp_path, {
        "format": "rtcl-scene", "version": 2, "integrator": "path",
        "camera": {"eye": [0, 0, 4], "look_at": [0, 0, 0], "fov": 45},
        "meshes": [{"file": "m.gltf", "smooth": False}, {"file": "q.obj", "smooth": False}]})
    image = read_pfm(render(scene, tmp_path, "e", "--size", "48x16", "--spp", "2"))
    # The quads' normals face +z, the camera: seen from the front.
    left, middle, right = image[8, 19], image[8, 24], image[8, 29]
    assert np.allclose(left, [2, 1, 0.5], rtol=1e-5), left
    assert np.allclose(middle, 0), middle
    assert np.allclose(right, [0.25, 0.5, 1], rtol=1e-5), right


@pytest.mark.parametrize("kernel", ["dynamic", pytest.param("wavefront", marks=pytest.mark.slow)])
def test_an_emitting_sphere_lights_a_plane_as_the_formula_says(tmp_path, kernel):
    """A diffuse plane of albedo rho under an emitting sphere of radius R
    whose centre is D above it: the point below reflects rho Le R^2 / D^2
    (0.5 * 8 / 16 = 0.25). The sphere's own surface does not shadow its
    light samples (RENDERING.md, next_event): when it did, 5 % was lost."""
    doc = {"format": "rtcl-scene", "version": 1, "integrator": "path", "max_depth": 0,
           "camera": {"eye": [0, 1, -6], "look_at": [0, 0, 0], "fov": 1},
           "spheres": [{"center": [0, 4, 0], "radius": 1,
                        "material": {"bsdf": {"type": "diffuse", "reflectance": [0, 0, 0]},
                                     "emission": [8, 8, 8]}}],
           "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0],
                       "material": {"bsdf": {"type": "diffuse",
                                             "reflectance": [0.5, 0.5, 0.5]}}}]}
    image = read_pfm(render(write_scene(tmp_path, doc), tmp_path, "sphere", "-k", kernel,
                            "--size", "8x8", "--spp", "1024"))
    assert np.allclose(image.mean(axis=(0, 1)), 0.25, rtol=0.01), image.mean(axis=(0, 1))


def write_hdr(path, rows, rle=True):
    """A Radiance .hdr of the given rows of (r, g, b) floats, each of the form
    m * 2^(e - 136) exactly (the tests use 0, 0.5 and 1), run-length encoded
    channel by channel or flat."""
    def rgbe(c):
        m = max(c)
        if m <= 0:
            return [0, 0, 0, 0]
        e = 0
        while m * 2.0 ** (136 - (e + 1)) < 128:  # m * 2^(136-e) in [128, 256)
            e -= 1
        while m * 2.0 ** (136 - e) >= 256:
            e += 1
        return [int(x * 2.0 ** (136 - e)) for x in c] + [e]
    height, width = len(rows), len(rows[0])
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width))
    for row in rows:
        pixels = [rgbe(c) for c in row]
        if rle:
            out += bytes([2, 2, width >> 8, width & 255])
            for ch in range(4):
                values = [p[ch] for p in pixels]
                for at in range(0, width, 128):
                    chunk = values[at:at + 128]
                    out += bytes([len(chunk)]) + bytes(chunk)
        else:
            for p in pixels:
                out += bytes(p)
    path.write_bytes(bytes(out))


@pytest.mark.parametrize("rle", [True, False])
def test_environment_map_lights_a_plane_by_its_upper_half(tmp_path, rle):
    """A map bright (radiance 1) in its upper half and black below: a diffuse
    plane facing up sees the whole bright hemisphere and reflects rho, a
    plane facing down sees nothing; the map sampled by its weights (its
    black rows never chosen) and by the BSDF, combined by MIS. The turn
    about +y changes nothing here."""
    width, height = 16, 8
    rows = [[(1.0, 1.0, 1.0) if k < height // 2 else (0.0, 0.0, 0.0)] * width
            for k in range(height)]
    write_hdr(tmp_path / "half.hdr", rows, rle)
    doc = {"format": "rtcl-scene", "version": 1, "integrator": "path", "max_depth": 0,
           "camera": {"eye": [0, 3, -3], "look_at": [0, 0, 0], "fov": 10},
           "environment": {"file": "half.hdr", "rotate": 70},
           "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0],
                       "material": {"bsdf": {"type": "diffuse",
                                             "reflectance": [0.6, 0.6, 0.6]}}}]}
    image = read_pfm(render(write_scene(tmp_path, doc), tmp_path, "half", "--size", "8x8",
                            "--spp", "256"))
    assert np.allclose(image.mean(axis=(0, 1)), 0.6, rtol=0.01), image.mean(axis=(0, 1))


def test_environment_map_is_seen_where_rays_leave(tmp_path):
    """The map's middle column looks along -z (rotate 0): a camera looking
    along -z at the horizon sees the middle column's colour, and with
    rotate 180 the edge's."""
    width, height = 8, 4
    rows = [[(0.5, 0.0, 0.0) if j in (3, 4) else (0.0, 0.0, 0.5) for j in range(width)]
            for k in range(height)]
    write_hdr(tmp_path / "m.hdr", rows)
    for rotate, colour in [(0, [0.5, 0, 0]), (180, [0, 0, 0.5])]:
        doc = {"format": "rtcl-scene", "version": 1, "integrator": "path",
               "camera": {"eye": [0, 0, 0], "look_at": [0, 0, -1], "fov": 5},
               "environment": {"file": "m.hdr", "rotate": rotate}}
        image = read_pfm(render(write_scene(tmp_path, doc), tmp_path, f"m{rotate}", "--size",
                                "4x4"))
        assert np.allclose(image, colour), (rotate, image[2, 2])


@pytest.mark.parametrize("content, message", [
    (None, 'environment.file: cannot read "sky.hdr": No such file or directory'),
    (b"P6\n1 1\n255\n...", '"sky.hdr" is not a Radiance HDR file (it does not start with "#?")'),
    (b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 2 +X 2\n", 'its FORMAT is "32-bit_rle_xyze"'),
    (b"#?RADIANCE\n\n+X 2 -Y 2\n", 'its size line is "+X 2 -Y 2"'),
    (b"#?RADIANCE\n\n-Y 10 +X 20000\n", '"sky.hdr" is 20000x10; rtcl reads 1 to 16384 pixels a side'),
    (b"#?RADIANCE\n\n-Y 3 +X 8\n" + bytes(32 * 2) + bytes([2, 2, 0, 8]),
     '"sky.hdr": its pixels end after row 2 of 3'),
    (b"#?RADIANCE\n\n-Y 16384 +X 16384\n" + bytes(100),
     '"sky.hdr": its header declares 16384x16384 pixels, at least 16842752 bytes, but the '
     'file holds 100 after its header'),
])
def test_environment_map_errors(tmp_path, content, message):
    if content is not None:
        (tmp_path / "sky.hdr").write_bytes(content)
    scene = box_with(tmp_path, lambda d: d.update(environment={"file": "sky.hdr"}))
    failure(rtcl(scene, "-o", tmp_path / "x.pfm"), message)
    assert not (tmp_path / "x.pfm").exists()


def test_an_emitter_is_no_light_at_its_own_points(tmp_path):
    """Inside an emitting sphere, whose emission leaves its outside only,
    nothing is lit: a point on the dome must not sample the dome itself
    (RENDERING.md, next_event), which rounding would otherwise decide."""
    doc = {"format": "rtcl-scene", "version": 1, "integrator": "path", "max_depth": 3,
           "camera": {"eye": [0.3, 0.2, -2], "look_at": [0, 0, 0], "fov": 60},
           "spheres": [{"center": [0, 0, 0], "radius": 5,
                        "material": {"bsdf": {"type": "diffuse", "reflectance": [0.8] * 3},
                                     "emission": [1, 1, 1]}}]}
    image = read_pfm(render(write_scene(tmp_path, doc), tmp_path, "dome", "--size", "16x16",
                            "--spp", "16"))
    assert image.max() == 0, image.mean()


def png_rgba(rows):
    """An 8-bit RGBA PNG of the rows (top first), written with zlib."""
    import struct
    import zlib
    h, w = len(rows), len(rows[0])
    raw = b"".join(b"\0" + b"".join(struct.pack(">BBBB", *p) for p in row) for row in rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def textured_quad(tmp_path, material, texels, **scene):
    """A glTF quad over [-1, 1]^2 facing +z, its texture coordinates 0 ... 1
    across, one texture (texels: a row of RGBA) clamped at its edges."""
    import base64
    import struct
    pos = struct.pack("<12f", -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0)
    uv = struct.pack("<8f", 0, 1, 1, 1, 1, 0, 0, 0)
    buf = pos + uv + struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                       "indices": 2, "material": 0}]}],
           "materials": [material],
           "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64,"
                        + base64.b64encode(buf).decode()}],
           "bufferViews": [{"buffer": 0, "byteLength": 48},
                           {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                           {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [-1, -1, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                         {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
           "samplers": [{"wrapS": 33071, "wrapT": 33071}],
           "textures": [{"source": 0, "sampler": 0}],
           "images": [{"uri": "data:image/png;base64,"
                       + base64.b64encode(png_rgba([texels])).decode()}]}
    (tmp_path / "q.gltf").write_text(json.dumps(doc))
    return write_scene(tmp_path, dict({
        "format": "rtcl-scene", "version": 2, "integrator": "path", "max_depth": 2,
        "camera": {"eye": [0, 0, 3], "look_at": [0, 0, 0], "fov": 40},
        "background": [1, 1, 1] if "emissiveFactor" not in material else [0, 0, 0],
        "meshes": [{"file": "q.gltf", "smooth": False}]}, **scene))


def test_a_models_emissive_texture_colours_its_emission(tmp_path):
    """glTF's emissiveTexture (sRGB) times emissiveFactor: red on the left
    half of the quad, blue on the right."""
    black = {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 1}
    scene = textured_quad(tmp_path, {"pbrMetallicRoughness": black,
                                     "emissiveFactor": [1, 0.5, 1],
                                     "emissiveTexture": {"index": 0}},
                          [(255, 0, 0, 255), (255, 0, 0, 255), (0, 0, 255, 255),
                           (0, 0, 255, 255)])
    image = read_pfm(render(scene, tmp_path, "e", "--size", "16x16", "--spp", "4"))
    assert np.allclose(image[8, 4], [1, 0, 0], atol=1e-6), image[8, 4]
    assert np.allclose(image[8, 11], [0, 0, 1], atol=1e-6), image[8, 11]


def test_a_models_metallic_roughness_texture_scales_its_roughness(tmp_path):
    """glTF's metallicRoughnessTexture (linear; G the roughness, B the
    metallic factor's scale): a white metal whose left half is smooth (G 0)
    mirrors the uniform environment of radiance 1, its right half (G 255,
    roughness 1) loses some of it to single scattering."""
    white = {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1, "roughnessFactor": 1,
             "metallicRoughnessTexture": {"index": 0}}
    scene = textured_quad(tmp_path, {"pbrMetallicRoughness": white},
                          [(0, 0, 255, 255), (0, 0, 255, 255), (0, 255, 255, 255),
                           (0, 255, 255, 255)])
    image = read_pfm(render(scene, tmp_path, "m", "--size", "16x16", "--spp", "64"))
    smooth, rough = image[6:10, 3:5].mean(), image[6:10, 11:13].mean()
    assert abs(smooth - 1) < 0.01, smooth
    assert rough < 0.97, rough


def test_a_models_normal_texture_turns_its_shading_normal(tmp_path):
    """glTF's normalTexture (linear, tangent space: x along dp/du): the
    quad's left half turned 30 degrees towards +x, towards a sun in the
    +x +z quarter, is lit by cos 15 degrees; its right half, flat, by cos 45."""
    white = {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 1}
    tilted, flat = (191, 128, 238, 255), (128, 128, 255, 255)
    scene = textured_quad(tmp_path, {"pbrMetallicRoughness": white,
                                     "normalTexture": {"index": 0}},
                          [tilted, tilted, flat, flat], background=[0, 0, 0],
                          lights=[{"direction": [-1, 0, -1], "color": [1, 1, 1]}])
    image = read_pfm(render(scene, tmp_path, "n", "--size", "16x16", "--spp", "16"))
    left, right = image[6:10, 3:5].mean(), image[6:10, 11:13].mean()
    assert right > 0.1, right
    assert 1.2 < left / right < 1.5, (left, right)  # cos 15 / cos 45 = 1.37


@pytest.mark.slow
def test_pieces_devices_and_mpi_ranks_give_the_one_device_image(tmp_path):
    """A path-traced image in row bands, with its samples split, and over
    three MPI ranks is the one-device image, byte for byte (the per-pixel
    sample sequence and the fixed-point sums do not depend on who traces)."""
    args = ["--size", "16x16", "--spp", "4"]
    plain = render(BOX, tmp_path, "plain", *args).read_bytes()
    bands = render(BOX, tmp_path, "bands", *args, "--devices", "0:0", "--piece-rows", "4")
    samples = render(BOX, tmp_path, "samples", *args, "--devices", "0:0", "--split", "samples")
    assert bands.read_bytes() == plain and samples.read_bytes() == plain
    if subprocess.run(["sh", "-c", "command -v mpirun"], capture_output=True).returncode:
        pytest.skip("no mpirun")
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "POCL_DEVICES": "pthread", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_orte_tmpdir_base": builds.ompi_session_base()}
    out = tmp_path / "mpi.pfm"
    result = subprocess.run(["mpirun", "--oversubscribe", "-np", "3", RTCL, "--mpi", str(BOX),
                             "-o", str(out), "-q", *args], capture_output=True, text=True,
                            cwd=ROOT, timeout=300, env=env)
    if "built without MPI" in result.stderr:
        pytest.skip("rtcl built without MPI")
    assert result.returncode == 0, result.stderr
    assert out.read_bytes() == plain


def test_verbose_says_what_lights_a_path_traced_scene(tmp_path):
    result = rtcl(BOX, "-v", "--size", "8x8", "--spp", "2", "-o", tmp_path / "v.pfm")
    assert result.returncode == 0, result.stderr
    assert ("rtcl: path integrator: 0 lights, 2 emitting triangles, 0 emitting spheres, "
            "no environment") in result.stderr.splitlines()
