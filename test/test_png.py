"""rtcl's own PNG writer (host/output/image_png.c): the pixels are the PPM's, every
chunk's CRC holds, the colour tags are OpenImageIO's; and a .ppm or .png run
never loads OpenImageIO (host/output/image_dl.c)."""
import os
import pathlib
import struct
import subprocess
import sys
import zlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import ppm  # noqa: E402


def rtcl(*args, cwd, env=None):
    result = subprocess.run([RTCL, "-q", "--size", "37x23", *args], capture_output=True,
                            text=True, cwd=cwd, timeout=300, env=env)
    return result


def chunks(data):
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    i, out = 8, []
    while i < len(data):
        length, kind = struct.unpack(">I4s", data[i:i + 8])
        body = data[i + 8:i + 8 + length]
        crc, = struct.unpack(">I", data[i + 8 + length:i + 12 + length])
        assert crc == zlib.crc32(kind + body), kind
        out.append((kind.decode(), body))
        i += 12 + length
    assert out[-1] == ("IEND", b"") and i == len(data)
    return out


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    return a if pa <= pb and pa <= pc else b if pb <= pc else c


def decode(path):
    """(width, height), RGB bytes: any of PNG's five row filters."""
    parts = chunks(path.read_bytes())
    width, height, depth, colour = struct.unpack(">IIBB", parts[0][1][:10])
    assert parts[0][0] == "IHDR" and depth == 8 and colour == 2
    raw = zlib.decompress(b"".join(body for kind, body in parts if kind == "IDAT"))
    stride, rows, previous = 3 * width, [], bytearray(3 * width)
    for y in range(height):
        kind, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 3] if x >= 3 else 0
            b, c = previous[x], previous[x - 3] if x >= 3 else 0
            line[x] = (line[x] + [0, a, b, (a + b) // 2, paeth(a, b, c)][kind]) & 255
        rows.append(bytes(line))
        previous = line
    assert len(raw) == height * (stride + 1)
    return (width, height), b"".join(rows)


@pytest.mark.parametrize("encoding", ["srgb", "linear"])
def test_the_png_holds_the_ppms_pixels_and_tags(tmp_path, encoding):
    for name in ["x.png", "x.ppm"]:
        result = rtcl("-o", name, "--encoding", encoding, cwd=tmp_path)
        assert result.returncode == 0, result.stderr
    assert decode(tmp_path / "x.png") == ppm.pixels(tmp_path / "x.ppm")
    tags = dict((kind, body) for kind, body in chunks((tmp_path / "x.png").read_bytes())
                if kind != "tEXt")
    texts = dict(body.split(b"\0", 1) for kind, body in
                 chunks((tmp_path / "x.png").read_bytes()) if kind == "tEXt")
    assert texts[b"Software"].startswith(b"rtcl ")
    assert texts[b"Description"].startswith(b"scene paper60.json (built-in), kernel dynamic, 37x23")
    if encoding == "linear":
        assert struct.unpack(">I", tags["gAMA"])[0] == 100000 and "sRGB" not in tags
        assert texts[b"oiio:ColorSpace"] == b"linear"
    else:
        assert struct.unpack(">I", tags["gAMA"])[0] == 45455 and tags["sRGB"] == b"\x03"
        assert texts[b"oiio:ColorSpace"] == b"sRGB" and len(tags["cHRM"]) == 32


def test_a_large_png_spans_several_idat_chunks(tmp_path):
    result = subprocess.run([RTCL, "-q", "-k", "naive", "--size", "400x300", "--depth", "1",
                             "-o", "x.png", "--work-map", "map.png"], capture_output=True,
                            text=True, cwd=tmp_path, timeout=300)
    assert result.returncode == 0, result.stderr
    (width, height), pixels = decode(tmp_path / "x.png")
    assert (width, height) == (400, 300) and len(pixels) == 400 * 300 * 3
    assert decode(tmp_path / "map.png")[0] == (400, 300)


def loaded_libraries(tmp_path, name):
    env = dict(os.environ, LD_DEBUG="files", LD_DEBUG_OUTPUT=str(tmp_path / "ld"))
    result = rtcl("-o", name, cwd=tmp_path, env=env)
    assert result.returncode == 0, result.stderr
    text = "".join(path.read_text(errors="replace") for path in tmp_path.glob("ld.*"))
    for path in tmp_path.glob("ld.*"):
        path.unlink()
    return text


def test_ppm_and_png_runs_do_not_load_openimageio(tmp_path):
    for name in ["x.ppm", "x.png", "x.pfm"]:
        text = loaded_libraries(tmp_path, name)
        assert "libOpenCL" in text  # the log is read
        assert "libOpenImageIO" not in text, name
    probe = rtcl("-o", "/nonexistent-dir/x.tif", cwd=tmp_path)
    if "no OpenImageIO" in probe.stderr:
        pytest.skip("a build without OpenImageIO")
    assert "libOpenImageIO" in loaded_libraries(tmp_path, "x.tif")
