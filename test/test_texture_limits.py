"""Texture limits checked before any decoding (issue 39 finding 14; docs/SCENE.md,
"Textures"): an image too large for a scene, or for the decoder, or whose decode
would not fit the import's memory limit, is refused from its header; a file over 2
GiB from its size; a 16-bit RGBA PNG within the limits loads, converted in place
rather than copied. PNG headers are generated here, their pixel data left short:
only the header is read before a refusal."""
import json
import os
import pathlib
import resource
import struct
import subprocess
import time
import zlib

import pytest

import builds

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
ASAN = builds.built_with_asan(RTCL)  # no memory limit under AddressSanitizer


def rtcl(*args):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True,
                          cwd=ROOT, timeout=300)


def chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))


def png_header_only(width, height, depth, color):
    """A PNG whose IHDR says width x height (color 6: RGBA, 2: RGB) and whose
    pixel data is one row: decoding it would fail, reading its header not."""
    row = b"\0" * (1 + width * {6: 4, 2: 3}[color] * depth // 8)
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, color, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(row)) + chunk(b"IEND", b""))


def png_zeros(width, height, depth):
    """A whole RGBA PNG of black, transparent texels, its rows compressed one by one."""
    row = b"\0" * (1 + width * 4 * depth // 8)
    z = zlib.compressobj(1)
    data = b"".join(z.compress(row) for _ in range(height)) + z.flush()
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, depth, 6, 0, 0, 0))
            + chunk(b"IDAT", data) + chunk(b"IEND", b""))


def scene(tmp_path):
    """A textured quad (q.obj, q.mtl naming t.png) and its scene."""
    (tmp_path / "q.obj").write_text(
        "mtllib q.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    (tmp_path / "q.mtl").write_text("newmtl t\nKd 1 1 1\nmap_Kd t.png\n")
    doc = {"format": "rtcl-scene", "version": 2,
           "camera": {"eye": [0, 0, 3], "look_at": [0, 0, 0]},
           "lights": [{"position": [0, 0, 5]}], "meshes": [{"file": "q.obj"}]}
    path = tmp_path / "s.json"
    path.write_text(json.dumps(doc))
    return path


PREFIX = 's.json: meshes[0].file: "q.obj": material "t": cannot read texture "t.png": '


def refusal(tmp_path, *options):
    path = scene(tmp_path)
    start = time.monotonic()
    result = rtcl(path, "-o", tmp_path / "o.ppm", "--size", "8x8", *options)
    assert result.returncode != 0 and not (tmp_path / "o.ppm").exists()
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0].replace(f"{tmp_path}/", ""), time.monotonic() - start


@pytest.mark.parametrize("color, words", [
    (6, "it is 16384x16384 texels of 16 bits (16 bytes a texel as floats), 4294967296 bytes"
        " on the device, more than the 4294967280 a scene may hold"),
    (2, "it is 16384x16384 texels of 16 bits (16 bytes a texel as floats), 4294967296 bytes"
        " on the device, more than the 4294967280 a scene may hold")])
def test_a_16_bit_image_too_large_for_a_scene_is_refused_from_its_header(tmp_path, color, words):
    """Before: RGBA said stb_image's stale "no SOI", RGB decoded for 49 s into 8.4 GB."""
    (tmp_path / "t.png").write_bytes(png_header_only(16384, 16384, 16, color))
    line, seconds = refusal(tmp_path)
    assert line == PREFIX + words
    assert seconds < 30


@pytest.mark.skipif(ASAN, reason="the import's memory limit is not applied under ASan")
def test_a_decode_that_would_not_fit_the_memory_limit_is_refused_from_its_header(tmp_path):
    """A 16384² 8-bit PNG (a few kB: a decompression bomb) needs 2 GiB to decode
    (its rows and its image): refused before any of it is inflated."""
    (tmp_path / "t.png").write_bytes(png_header_only(16384, 16384, 8, 6))
    line, _ = refusal(tmp_path, "--mesh-memory-limit", "1536")
    assert line == PREFIX + (
        "it is 16384x16384 texels; decoding it takes about 2049 MiB, more than the import's"
        " memory limit of 1536 MiB leaves (--mesh-memory-limit or RTCL_MESH_MEMORY_LIMIT)")


@pytest.mark.skipif(ASAN, reason="the import's memory limit is not applied under ASan")
def test_a_file_over_2_GiB_is_refused_from_its_size_before_it_is_read(tmp_path):
    """A sparse file: before, it was read whole (here: out of memory under the limit)."""
    scene(tmp_path)
    with open(tmp_path / "t.png", "wb") as f:
        f.truncate(2**31 + 1)
    line, _ = refusal(tmp_path, "--mesh-memory-limit", "1024")
    assert line == PREFIX + "it has 2147483649 bytes, more than 2 GiB"


@pytest.mark.skipif(ASAN, reason="the import's memory limit is not applied under ASan")
def test_a_16_bit_rgba_png_within_the_limits_loads_under_a_tight_memory_limit(tmp_path):
    """4096² 16-bit RGBA: 256 MiB of float texels. Its 16-bit image is made floats in
    place and the first texture's buffer is not copied: the helper needs about 260 MiB,
    where it took more than 500 (refused under 400 before)."""
    path = scene(tmp_path)
    (tmp_path / "t.png").write_bytes(png_zeros(4096, 4096, 16))
    result = rtcl(path, "-o", tmp_path / "o.ppm", "--size", "8x8", "-v",
                  "--mesh-memory-limit", "400")
    assert result.returncode == 0, result.stderr
    assert 'texture "t.png": 4096x4096 float linear, repeat/repeat, 268435456 bytes' \
        in result.stderr


def address_space_needed(path, out, low, high, step=16):
    """The least address space (MiB, to step) under which rtcl renders path:
    bisected between low (too little) and high (enough)."""
    def renders(mib):
        def limit():
            resource.setrlimit(resource.RLIMIT_AS, (mib << 20, mib << 20))
        result = subprocess.run([RTCL, path, "-o", out, "--size", "8x8"], cwd=ROOT,
                                capture_output=True, preexec_fn=limit, timeout=300)
        return result.returncode == 0
    assert renders(high), f"rtcl does not render {path} in {high} MiB"
    while high - low > step:
        middle = (low + high) // 2
        low, high = (low, middle) if renders(middle) else (middle, high)
    return high


@pytest.mark.skipif(ASAN, reason="AddressSanitizer reserves terabytes of address space")
def test_a_large_texture_is_held_twice_at_most_while_rendering(tmp_path):
    """A 4096² 16-bit texture (256 MiB of float texels) renders within the address
    space the same scene needs with an 8² texture plus three times the texels:
    rtcl holds two copies, the scene's and the device buffer's (the helper that
    decodes it is a process of its own). Before, the packed scene block held a
    third: it needed 3.4 times the texels more (875 MiB), now 2.4 (612 MiB, the
    allocators' slack included); its peak RSS went from 864 MB to 602 MB."""
    texels = 4096 * 4096 * 16 >> 20
    path = scene(tmp_path)
    (tmp_path / "t.png").write_bytes(png_zeros(8, 8, 16))
    small = address_space_needed(path, tmp_path / "o.ppm", 0, 4096)
    (tmp_path / "t.png").write_bytes(png_zeros(4096, 4096, 16))
    limit = small + 3 * texels

    def limited():
        resource.setrlimit(resource.RLIMIT_AS, (limit << 20, limit << 20))
    result = subprocess.run([RTCL, path, "-o", tmp_path / "o.ppm", "--size", "8x8"], cwd=ROOT,
                            capture_output=True, text=True, preexec_fn=limited, timeout=300)
    assert result.returncode == 0, f"in {limit} MiB ({small} + 3 x {texels}): {result.stderr}"
