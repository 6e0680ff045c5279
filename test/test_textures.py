"""Textures and alpha cut-outs from mesh files (docs/RENDERING.md "Textures" and
"Alpha cut-out", docs/SCENE.md "Textures"): texels where the texture coordinates
put them, wrap modes, bilinear filtering between texel centres, the sRGB decode,
cut-outs for primary and shadow rays, every kernel alike and the reference near,
scenes without textures built as before, and every message. Models and PNGs are
generated here, tiny."""
import base64
import json
import math
import os
import pathlib
import struct
import subprocess
import zlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
MODELS = pathlib.Path("/usr/share/assimp/models")


def rtcl(*args):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


def png(rows, depth=8):
    """A PNG of RGBA rows (top first), 8 or 16 bits, written with zlib."""
    h, w = len(rows), len(rows[0])
    fmt = ">" + ("B" if depth == 8 else "H") * 4
    raw = b"".join(b"\0" + b"".join(struct.pack(fmt, *p) for p in row) for row in rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def read_pfm(path):
    """Rows top first of (r, g, b) floats."""
    data = path.read_bytes()
    header = data.split(b"\n", 3)
    w, h = map(int, header[1].split())
    scale = float(header[2])
    values = struct.unpack(("<" if scale < 0 else ">") + "f" * (3 * w * h), header[3][:12 * w * h])
    rows = [[values[3 * (y * w + x):3 * (y * w + x) + 3] for x in range(w)] for y in range(h)]
    return rows[::-1]  # PFM stores the bottom row first


def ppm_pixels(path):
    """A PPM's pixel bytes, past its header and comment lines."""
    data, words, at = path.read_bytes(), 0, 0
    while words < 4:
        while data[at:at + 1].isspace():
            at += 1
        if data[at:at + 1] == b"#":
            at = data.index(b"\n", at) + 1
            continue
        while not data[at:at + 1].isspace():
            at += 1
        words += 1
    return data[at + 1:]


def srgb_to_linear(c):
    x = c / 255
    return x / 12.92 if x <= 0.04045 else ((x + 0.055) / 1.055) ** 2.4


# A 4x4 texture, rows top first: primaries, a mid-grey (128) and black/white.
RED, GREEN, BLUE, GREY = (255, 0, 0, 255), (0, 255, 0, 255), (0, 0, 255, 255), (128, 128, 128, 255)
WHITE, BLACK = (255, 255, 255, 255), (0, 0, 0, 255)
TEXELS = [[RED, GREEN, BLUE, GREY],
          [GREY, WHITE, BLACK, RED],
          [BLUE, BLACK, GREEN, WHITE],
          [WHITE, GREY, RED, BLUE]]
SIDE = 36  # 9 pixels a texel: pixel 9i + 4 is at texel i's centre


def wrap(k, n, mode):
    if mode == "clamp":
        return min(max(k, 0), n - 1)
    if mode == "mirror":
        m = k % (2 * n)
        return m if m < n else 2 * n - 1 - m
    return k % n


def expected(texels, u, v, modes=("repeat", "repeat")):
    """RENDERING.md's lookup in double: linear RGBA at (u, v), v up."""
    h, w = len(texels), len(texels[0])
    x, y = u * w - 0.5, (1 - v) * h - 0.5
    i, j = math.floor(x), math.floor(y)
    fx, fy = x - i, y - j

    def texel(a, b):
        p = texels[wrap(b, h, modes[1])][wrap(a, w, modes[0])]
        return [srgb_to_linear(c) for c in p[:3]] + [p[3] / 255]
    lerp = lambda a, b, f: [p + f * (q - p) for p, q in zip(a, b)]
    return lerp(lerp(texel(i, j), texel(i + 1, j), fx), lerp(texel(i, j + 1), texel(i + 1, j + 1), fx), fy)


def quad_scene(tmp_path, texels=TEXELS, uv=(0, 1), clamp=False, extra_mtl="", mesh=None):
    """A unit-less quad filling the image exactly (seen from +z, 53.13°), its
    texture coordinates from uv[0] to uv[1] on both axes, lit by an ambient of 1
    only, so that a pixel's linear colour is the texture's there."""
    (tmp_path / "t.png").write_bytes(png(texels))
    a, b = uv
    (tmp_path / "q.obj").write_text(
        "mtllib q.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
        f"vt {a} {a}\nvt {b} {a}\nvt {b} {b}\nvt {a} {b}\nusemtl t\n"
        "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    (tmp_path / "q.mtl").write_text("newmtl t\nKd 1 1 1\nKa 1 1 1\nKs 0 0 0\n"
                                    f"map_Kd {'-clamp on ' if clamp else ''}t.png\n{extra_mtl}")
    doc = {"format": "rtcl-scene", "version": 2,
           "image": {"width": SIDE, "height": SIDE},
           "camera": {"eye": [0, 0, 2], "look_at": [0, 0, 0], "fov": math.degrees(2 * math.atan(0.5))},
           "ambient": [1, 1, 1], "background": [0.5, 0.25, 0.125],
           "meshes": [dict({"file": "q.obj", "smooth": False}, **(mesh or {}))]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    return path


def render(path, *options, name="o.pfm"):
    out = path.parent / name
    result = rtcl(path, "-o", out, *options)
    assert result.returncode == 0, result.stderr
    return out, result.stderr


def pixel_uv(x, y, lo=0.0, hi=1.0):
    return lo + (hi - lo) * (x + 0.5) / SIDE, lo + (hi - lo) * (1 - (y + 0.5) / SIDE)


def test_texels_lie_where_the_coordinates_put_them_srgb_decoded(tmp_path):
    image = read_pfm(render(quad_scene(tmp_path, clamp=True))[0])
    for j in range(4):
        for i in range(4):
            got = image[9 * j + 4][9 * i + 4]
            want = [srgb_to_linear(c) for c in TEXELS[j][i][:3]]
            assert all(abs(g - w) < 1e-4 for g, w in zip(got, want)), (i, j, got, want)
    # the mid-grey 8-bit texel 128 is 0.2158605 linear (E^-1(128/255))
    assert abs(image[4][31][0] - 0.2158605) < 1e-5


def test_bilinear_filtering_between_texel_centres(tmp_path):
    image = read_pfm(render(quad_scene(tmp_path, clamp=True))[0])
    for x, y in ((8, 4), (9, 13), (13, 22), (17, 17), (0, 0), (35, 35), (22, 30)):
        want = expected(TEXELS, *pixel_uv(x, y), ("clamp", "clamp"))[:3]
        assert all(abs(g - w) < 2e-4 for g, w in zip(image[y][x], want)), (x, y)
    # half-way between two centres: their mean (the pixel's centre is 4.5 px off,
    # half a texel: x = 9 i + 8.5 lies between pixels 8 and 9)
    a, b = image[4][8], image[4][9]
    mean = [(srgb_to_linear(p) + srgb_to_linear(q)) / 2 for p, q in zip(RED[:3], GREEN[:3])]
    assert all(min(p, q) - 1e-4 <= m <= max(p, q) + 1e-4 for p, q, m in zip(a, b, mean))


def gltf_quad(tmp_path, sampler, alpha_mode=None, texels=TEXELS, lo=-1.0, hi=2.0, name="q.gltf"):
    """The quad of quad_scene as glTF, its texture embedded in a data: URI,
    coordinates lo ... hi (glTF's v points down the image)."""
    pos = struct.pack("<12f", -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0)
    uv = struct.pack("<8f", lo, hi, hi, hi, hi, lo, lo, lo)
    idx = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    buf = pos + uv + idx
    material = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0,
                                         "roughnessFactor": 1}}
    if alpha_mode:
        material["alphaMode"] = alpha_mode
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2,
                                       "material": 0}]}],
           "materials": [material],
           "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64,"
                        + base64.b64encode(buf).decode()}],
           "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                           {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [-1, -1, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                         {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
           "samplers": [sampler], "textures": [{"source": 0, "sampler": 0}],
           "images": [{"uri": "data:image/png;base64," + base64.b64encode(png(texels)).decode()}]}
    (tmp_path / name).write_text(json.dumps(doc))
    return name


@pytest.mark.parametrize("modes", [("repeat", "repeat"), ("clamp", "mirror"), ("mirror", "clamp")])
def test_wrap_modes_as_the_glTF_sampler_says(tmp_path, modes):
    codes = {"repeat": 10497, "clamp": 33071, "mirror": 33648}
    path = quad_scene(tmp_path)
    doc = json.loads(path.read_text())
    doc["meshes"][0]["file"] = gltf_quad(tmp_path, {"wrapS": codes[modes[0]], "wrapT": codes[modes[1]]})
    doc["ambient"] = [1 / 0.96] * 3  # glTF's ka is kd = 1 - 0.04 (metallic 0)... see below
    path.write_text(json.dumps(doc))
    image = read_pfm(render(path)[0])
    ka = 1.0  # metallic 0, transmission 0: kd = ka = 1
    for x, y in ((2, 2), (5, 30), (17, 17), (30, 6), (33, 33), (11, 26)):
        u, v = pixel_uv(x, y, -1.0, 2.0)
        want = [c * ka / 0.96 for c in expected(TEXELS, u, v, modes)[:3]]
        assert all(abs(g - w) < 3e-4 for g, w in zip(image[y][x], want)), (modes, x, y, image[y][x], want)


def cutout_scene(tmp_path, alpha_mode):
    """The quad (left half of its texture alpha 0, right half 1) at z = 0 over a
    white floor quad at z = -1 lit straight along -z, seen from +z: the cut-out half
    shows the floor, lit, the other the texture; with OPAQUE both are the texture."""
    half = [[(255, 0, 0, 0)] * 2 + [(255, 0, 0, 255)] * 2 for _ in range(4)]
    name = gltf_quad(tmp_path, {"wrapS": 33071, "wrapT": 33071}, alpha_mode, half, 0.0, 1.0)
    doc = {"format": "rtcl-scene", "version": 2,
           "image": {"width": 24, "height": 12},
           "camera": {"eye": [0, 0, 4], "look_at": [0, 0, 0], "fov": 40},
           "ambient": [0, 0, 0], "background": [0, 0, 0],
           "lights": [{"direction": [0, 0, -1], "color": [1, 1, 1]}],
           "meshes": [{"file": name, "smooth": False}],
           "triangles": [{"vertices": [[-9, -9, -1], [9, -9, -1], [9, 9, -1]], "material": {"color": [0, 1, 0]}},
                         {"vertices": [[-9, -9, -1], [9, 9, -1], [-9, 9, -1]], "material": {"color": [0, 1, 0]}}]}
    path = tmp_path / ("c-%s.json" % alpha_mode)
    path.write_text(json.dumps(doc))
    return path


def test_alpha_cut_out_lets_primary_and_shadow_rays_through(tmp_path):
    masked = read_pfm(render(cutout_scene(tmp_path, "MASK"), name="m.pfm")[0])
    opaque = read_pfm(render(cutout_scene(tmp_path, "OPAQUE"), name="o.pfm")[0])
    path = cutout_scene(tmp_path, "MASK")
    doc = json.loads(path.read_text())
    del doc["meshes"]
    path.write_text(json.dumps(doc))
    floor = read_pfm(render(path, name="f.pfm")[0])
    left, right = masked[6][10], masked[6][13]
    # the cut-out half: the green floor behind, lit as without the quad (the
    # shadow ray passed the quad too)
    assert left[1] > 0.9 and left[1] > 2 * left[0], left
    assert left == floor[6][10]
    assert all(masked[y][x] == floor[y][x] for y in range(12) for x in range(12))
    # the opaque half: the texture's red, lit
    assert right[0] > 0.5 and right[1] < 0.5 * right[0], right
    # OPAQUE: the quad is red on both halves
    assert opaque[6][10][0] > 0.5 and opaque[6][10][1] < 0.5 * opaque[6][10][0]


def test_cut_out_quad_casts_a_shadow_only_where_it_is_opaque(tmp_path):
    path = cutout_scene(tmp_path, "MASK")
    doc = json.loads(path.read_text())
    doc["lights"] = [{"direction": [0, -1, -1], "color": [1, 1, 1]}]  # shadow moved down the floor
    doc["camera"] = {"eye": [0, 0, 4], "look_at": [0, -1, -1], "fov": 30}
    path.write_text(json.dumps(doc))
    image = read_pfm(render(path)[0])
    doc["meshes"][0]["material"] = {"color": [1, 0, 0]}  # the file's material forced: no cut-out
    path.write_text(json.dumps(doc))
    solid = read_pfm(render(path, name="solid.pfm")[0])
    # where the solid quad shadows the floor, the cut-out one shadows only half
    shadowed = [(x, y) for y in range(12) for x in range(24)
                if solid[y][x][1] == 0 and solid[y][x][0] == 0]
    assert shadowed
    lit_now = [(x, y) for x, y in shadowed if image[y][x][1] > 0]
    assert 0 < len(lit_now) < len(shadowed)


KERNELS = ["serial", "naive", "cyclic", "dynamic", "persistent", "wavefront"]


def test_kernels_agree_and_the_reference_is_near(tmp_path):
    path = cutout_scene(tmp_path, "MASK")
    doc = json.loads(path.read_text())
    doc["lights"] = [{"direction": [0.3, -1, -1], "color": [1, 1, 1]}]
    doc["camera"] = {"eye": [1, 0.5, 4], "look_at": [0, -0.5, -1], "fov": 40}
    doc["meshes"].append({"file": "q.obj", "translate": [0.5, 0.2, 0.3], "scale": 0.4})
    path.write_text(json.dumps(doc))
    quad_scene(tmp_path)  # q.obj and t.png beside it
    images = {}
    for k in ["dynamic", "wavefront", "reference"]:
        out, _ = render(path, "-k", k, "--size", "48x24", name=f"{k}.ppm")
        images[k] = ppm_pixels(out)
    assert images["wavefront"] == images["dynamic"]
    # PSNR >= 40 dB, at most 0.1 % of the values off by more than 2/255 (as
    # the kernel tests ask of every shipped scene)
    diff = [abs(a - b) for a, b in zip(images["reference"], images["dynamic"])]
    mse = sum(d * d for d in diff) / len(diff)
    assert mse == 0 or 10 * math.log10(255 ** 2 / mse) >= 40, mse
    assert sum(d > 2 for d in diff) <= 0.001 * len(diff)


@pytest.mark.slow
def test_every_kernel_gives_the_same_textured_image(tmp_path):
    path = quad_scene(tmp_path, uv=(-0.3, 1.7), extra_mtl="map_d t.png\n")
    seen = set()
    for k in KERNELS:
        out, _ = render(path, "-k", k, name=f"{k}.ppm")
        seen.add(ppm_pixels(out))
    assert len(seen) == 1


def test_scenes_without_textures_build_the_program_of_before(tmp_path):
    path = quad_scene(tmp_path)
    doc = json.loads(path.read_text())
    doc["meshes"][0]["material"] = {"color": [1, 1, 1]}
    path.write_text(json.dumps(doc))
    _, err = render(path, "-v")
    assert "build options:" in err and "RTCL_TEXTURES" not in err
    _, err = render(quad_scene(tmp_path), "-v", "--stats", tmp_path / "st.json")
    assert "-DRTCL_TEXTURES" in err
    assert 'meshes[0] "q.obj": texture "t.png": 4x4 8-bit sRGB, repeat/repeat, 64 bytes' in err
    stats = json.loads((tmp_path / "st.json").read_text())
    assert stats["textures"] == [{"mesh": 0, "name": "t.png", "width": 4, "height": 4,
                                  "format": "8-bit sRGB", "wrap_s": "repeat", "wrap_t": "repeat",
                                  "bytes": 64}]
    assert stats["texture_bytes"] == 64


def test_a_16_bit_texture_is_decoded_to_float(tmp_path):
    path = quad_scene(tmp_path, clamp=True)
    (tmp_path / "t.png").write_bytes(png([[(32768, 65535, 0, 65535)] * 2] * 2, depth=16))
    out, err = render(path, "-v")
    assert "2x2 float linear, clamp/clamp, 64 bytes" in err
    r, g, b = read_pfm(out)[18][18]
    x = 32768 / 65535
    assert abs(r - ((x + 0.055) / 1.055) ** 2.4) < 1e-5 and abs(g - 1) < 1e-6 and b == 0


@pytest.mark.parametrize("name, setup, words", [
    ("missing", lambda d: None, 'cannot read texture "t.png": No such file or directory'),
    ("outside", lambda d: (d.parent / "o.png").write_bytes(png(TEXELS)),
     'cannot read texture "../o.png": it lies outside the folder of "q.obj"'),
    ("fifo", lambda d: os.mkfifo(d / "t.png"), 'cannot read texture "t.png": it is not a regular file'),
    ("not an image", lambda d: (d / "t.png").write_text("hello"),
     'cannot read texture "t.png": the image decoder (stb_image) says "unknown image type"'),
    ("too wide", lambda d: (d / "t.png").write_bytes(png([[RED] * 16385])),
     'cannot read texture "t.png": it is 16385x1 texels, more than the 16384 a side rtcl reads'),
])
def test_a_texture_that_cannot_be_read_is_one_message_or_with_warn_a_warning(tmp_path, name, setup, words):
    folder = tmp_path / "m"
    folder.mkdir()
    path = quad_scene(folder)
    (folder / "t.png").unlink()
    if name == "outside":
        (folder / "q.mtl").write_text("newmtl t\nKd 1 1 1\nmap_Kd ../o.png\n")
        words = words.replace("t.png", "../o.png") if "t.png" in words else words
    setup(folder)
    out = folder / "o.ppm"
    result = rtcl(path, "-o", out, "--size", "8x8")
    message = f'{path}: meshes[0].file: "q.obj": material "t": {words}'
    assert result.returncode == 1 and result.stderr == message + "\n" and not out.exists()
    doc = json.loads(path.read_text())
    doc["meshes"][0]["missing_textures"] = "warn"
    path.write_text(json.dumps(doc))
    result = rtcl(path, "-o", out, "--size", "8x8", "-q")
    assert result.returncode == 0 and out.exists()
    assert result.stderr == f"rtcl: warning: {message}; its material renders without it\n"


@pytest.mark.parametrize("value, words", [('"skip"', 'got "skip"'), ("1", "got an integer"),
                                          ("true", "got true")])
def test_missing_textures_takes_error_or_warn(tmp_path, value, words):
    path = quad_scene(tmp_path)
    path.write_text(path.read_text().replace('"smooth": false', '"smooth": false, "missing_textures": ' + value))
    out = tmp_path / "o.ppm"
    result = rtcl(path, "-o", out)
    assert result.returncode == 1 and not out.exists()
    assert result.stderr.startswith(f'{path}: meshes[0].missing_textures: must be "error" or "warn", ')
    assert words.split()[-1] in result.stderr and result.stderr.count("\n") == 1


@pytest.mark.skipif(not (MODELS / "OBJ" / "spider.obj").is_file(),
                    reason="Debian's assimp-testmodels is not installed")
def test_the_spider_loads_with_its_textures(tmp_path):
    doc = {"format": "rtcl-scene", "version": 2,
           "camera": {"eye": [0, 40, 120], "look_at": [0, 0, 0]},
           "lights": [{"position": [0, 100, 100]}],
           "meshes": [{"file": str(MODELS / "OBJ" / "spider.obj")}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    out, err = render(path, "--size", "32x24", "-v", name="o.ppm")
    assert 'texture ".\\SpiderTex.jpg": 249x250 8-bit sRGB, repeat/repeat, 249000 bytes' in err
    assert "warning" not in err


def test_flops_of_a_texture_lookup_and_a_cut_out_test(tmp_path):
    """RENDERING.md's rules: a textured hit adds 12 (coordinates) + 43 (lookup) + 3
    (C ⊙ T) = 58 to its shading; a cut-out test with an alpha texture 12 + 43 + 1 =
    56 where a hit would be taken (twice where a ray meets both triangles of the
    quad on their shared edge at one t)."""
    import numpy
    path = quad_scene(tmp_path, clamp=True, extra_mtl="map_d t.png\n")
    doc = json.loads(path.read_text())
    maps = {}
    for name, mesh in (("plain", {"material": {"color": [1, 1, 1]}}), ("textured", {})):
        path.write_text(json.dumps(dict(doc, meshes=[dict(doc["meshes"][0], **mesh)])))
        render(path, "--work-map", tmp_path / f"{name}.npy", name=f"{name}.pfm")
        maps[name] = numpy.load(tmp_path / f"{name}.npy").astype(numpy.int64)
    extra = maps["textured"] - maps["plain"]
    off_diagonal = numpy.fliplr(~numpy.eye(SIDE, dtype=bool))
    assert set(numpy.unique(extra[off_diagonal])) == {58 + 56}
    assert set(numpy.unique(extra[~off_diagonal])) <= {58 + 56, 58 + 2 * 56}
