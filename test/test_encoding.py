"""--encoding srgb|linear: how the 8-bit formats store the linear colours
(RENDERING.md, "Writing the image"), and the tags that say so."""
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import ppm  # noqa: E402
SMALL = ["--size", "40x30"]


def rtcl(*args, cwd):
    result = subprocess.run([RTCL, *SMALL, "-q", *args], capture_output=True, text=True,
                            cwd=cwd, timeout=300)
    assert result.returncode == 0, result.stderr
    return result


def ppm_pixels(path):
    """The pixel bytes of a binary PPM, after its header and comments."""
    return ppm.pixels(path)[1]


def pfm_values(path):
    """The floats of a little-endian PFM, rows top first, as PPM stores them."""
    np = pytest.importorskip("numpy")
    data = path.read_bytes()
    header = data.split(b"\n", 3)
    width, height = map(int, header[1].split())
    values = np.frombuffer(header[3], dtype="<f4").reshape(height, width * 3)
    return values[::-1].reshape(-1)


def expected_bytes(values, srgb):
    np = pytest.importorskip("numpy")
    c = np.clip(np.nan_to_num(values.astype(np.float64), nan=0.0), 0.0, 1.0)
    if srgb:
        c = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.floor(255.0 * c + 0.5).astype(np.uint8).tobytes()


@pytest.mark.parametrize("options, srgb", [([], True), (["--encoding", "srgb"], True),
                                           (["--encoding", "linear"], False)])
def test_8bit_bytes_follow_the_encoding(tmp_path, options, srgb):
    rtcl("-o", "linear.pfm", cwd=tmp_path)
    rtcl("-o", "image.ppm", *options, cwd=tmp_path)
    values = pfm_values(tmp_path / "linear.pfm")
    assert ppm_pixels(tmp_path / "image.ppm") == expected_bytes(values, srgb)
    header = (tmp_path / "image.ppm").read_bytes()[:200]
    assert (b"# Encoding: sRGB" if srgb else b"# Encoding: linear") in header


def test_float_formats_ignore_the_encoding(tmp_path):
    rtcl("-o", "a.pfm", cwd=tmp_path)
    rtcl("-o", "b.pfm", "--encoding", "linear", cwd=tmp_path)
    assert (tmp_path / "a.pfm").read_bytes() == (tmp_path / "b.pfm").read_bytes()


def test_a_bad_encoding_is_a_usage_error(tmp_path):
    result = subprocess.run([RTCL, "--encoding", "gamma"], capture_output=True, text=True,
                            cwd=tmp_path, timeout=60)
    assert result.returncode == 2
    assert result.stderr == 'rtcl: --encoding: expected srgb or linear, got "gamma"\n'
    assert os.listdir(tmp_path) == []


needs_oiiotool = pytest.mark.skipif(shutil.which("oiiotool") is None,
                                    reason="oiiotool (openimageio-tools) is not installed")


@needs_oiiotool
@pytest.mark.parametrize("name, options, tag", [
    ("a.png", [], '"sRGB"'), ("b.png", ["--encoding", "linear"], '"linear"'),
    ("c.jpg", [], '"sRGB"'), ("d.exr", [], '"Linear"'),
    ("e.exr", ["--encoding", "srgb"], '"Linear"')])
def test_tags_read_back_through_openimageio(tmp_path, name, options, tag):
    result = subprocess.run([RTCL, *SMALL, "-q", "-o", name, *options], capture_output=True,
                            text=True, cwd=tmp_path, timeout=300)
    if "no OpenImageIO" in result.stderr:
        pytest.skip("a build without OpenImageIO")
    assert result.returncode == 0, result.stderr
    info = subprocess.run(["oiiotool", "--info", "-v", name], capture_output=True, text=True,
                          cwd=tmp_path, timeout=60).stdout
    assert f"oiio:ColorSpace: {tag}" in info, info


# ---- radiance that overflows float (issue 24, finding 12) -----------------------

FLT_MAX = 3.4028234663852886e38
RGBE_MAX = 1.7014117e38  # Radiance HDR: 2^127 and up wrap to black


def hot_scene(directory):
    """two_balls with lights, colours and diffuse coefficients of 1e18 (all
    allowed): light x colour x kd = 1e54 overflows float on the lit spheres."""
    import json
    scene = json.loads((ROOT / "scenes" / "two_balls.json").read_text())
    for light in scene["lights"]:
        light["color"] = [1e18, 1e18, 1e18]
    for material in scene["materials"].values():
        material["color"] = [1e18, 1e18, 1e18]
        material["diffuse"] = 1e18
    path = directory / "hot.json"
    path.write_text(json.dumps(scene))
    return path


@pytest.mark.parametrize("kernel", ["dynamic", "reference"])
def test_overflowing_radiance_is_written_as_the_largest_float_never_inf(tmp_path, kernel):
    np = pytest.importorskip("numpy")
    rtcl("-s", str(hot_scene(tmp_path)), "-k", kernel, "-o", "hot.pfm", cwd=tmp_path)
    values = pfm_values(tmp_path / "hot.pfm")
    assert np.isfinite(values).all(), "inf or NaN written"
    assert (values == np.float32(FLT_MAX)).sum() > 100  # the lit spheres, clamped
    assert values.min() > 0


@needs_oiiotool
@pytest.mark.parametrize("name, largest", [("hot.exr", FLT_MAX), ("hot.hdr", RGBE_MAX)])
def test_overflowing_radiance_in_exr_and_hdr_is_the_largest_value_never_black(tmp_path, name,
                                                                              largest):
    np = pytest.importorskip("numpy")
    scene = hot_scene(tmp_path)
    result = subprocess.run([RTCL, *SMALL, "-q", "-s", str(scene), "-o", name],
                            capture_output=True, text=True, cwd=tmp_path, timeout=300)
    if "no OpenImageIO" in result.stderr:
        pytest.skip("a build without OpenImageIO")
    assert result.returncode == 0, result.stderr
    rtcl("-s", str(scene), "-o", "hot.pfm", cwd=tmp_path)
    dump = subprocess.run(["oiiotool", "--dumpdata", name], capture_output=True, text=True,
                          check=True, cwd=tmp_path, timeout=60).stdout
    back = np.array([float(v) for line in dump.splitlines() if "Pixel (" in line
                     for v in line.split(":")[1].split()])
    direct = pfm_values(tmp_path / "hot.pfm")
    assert np.isfinite(back).all()
    overflowed = direct == np.float32(FLT_MAX)
    assert overflowed.sum() > 100
    # Where float overflowed, the file holds (about) its largest value, not 0.
    assert (back[overflowed] >= 0.99 * largest).all(), back[overflowed].min()
    assert back.max() <= largest
