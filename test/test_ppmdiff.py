"""tools/imgdiff.py (rtcl-imgdiff; ppmdiff.py, rtcl-ppmdiff, its old name): pixel
comparison of images whose headers differ, in every format rtcl writes."""
import math
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import images, ppm  # noqa: E402


def write_ppm(path, comment, pixels, width=2, height=1):
    path.write_bytes(b"P6\n# %s\n%d %d\n255\n" % (comment, width, height) + bytes(pixels))


def test_headers_are_ignored_and_differences_counted(tmp_path):
    write_ppm(tmp_path / "a.ppm", b"kernel naive", [1, 2, 3, 4, 5, 6])
    write_ppm(tmp_path / "b.ppm", b"kernel dynamic, longer comment", [1, 2, 3, 4, 5, 6])
    write_ppm(tmp_path / "c.ppm", b"x", [1, 2, 4, 4, 5, 9])
    assert ppm.pixels(tmp_path / "a.ppm") == ((2, 1), bytes([1, 2, 3, 4, 5, 6]))
    _, a = ppm.pixels(tmp_path / "a.ppm")
    assert ppm.differences(a, ppm.pixels(tmp_path / "b.ppm")[1]) == (0, 0)
    assert ppm.differences(a, ppm.pixels(tmp_path / "c.ppm")[1]) == (2, 3)
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "ppmdiff.py"),
                             str(tmp_path / "a.ppm"), str(tmp_path / "b.ppm"),
                             str(tmp_path / "c.ppm")], capture_output=True, text=True)
    assert result.returncode == 0
    assert "b.ppm: same pixels as" in result.stdout
    assert "c.ppm: 2 values differ (max 3/255)" in result.stdout


def test_size_mismatch_fails(tmp_path):
    write_ppm(tmp_path / "a.ppm", b"x", [0] * 6)
    write_ppm(tmp_path / "b.ppm", b"x", [0] * 3, width=1)
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "ppmdiff.py"),
                             str(tmp_path / "a.ppm"), str(tmp_path / "b.ppm")],
                            capture_output=True, text=True)
    assert result.returncode == 1 and "size" in result.stdout


# ---- rtcl-imgdiff (rtcl-ppmdiff is its old name): every format rtcl writes ---------------

RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))


def imgdiff(*args, tool="imgdiff.py"):
    return subprocess.run([sys.executable, str(ROOT / "tools" / tool), *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def render(path, *options):
    """An rtcl render of 24x16 pixels to path (its format from the name)."""
    result = subprocess.run([RTCL, "-q", "--size", "24x16", "-o", str(path), *options],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr


@pytest.fixture(scope="module")
def renders(tmp_path_factory):
    """The default render as PNG, PPM and PFM, by another kernel, and at depth 1."""
    if not os.access(RTCL, os.X_OK):
        pytest.skip(f"{RTCL} is not built")
    folder = tmp_path_factory.mktemp("renders")
    for name in ("a.png", "a.ppm", "a.pfm"):
        render(folder / name)
    render(folder / "naive.png", "-k", "naive")
    render(folder / "shallow.png", "--depth", "1")
    render(folder / "shallow.pfm", "--depth", "1")
    return folder


def test_png_ppm_and_pfm_are_read_as_rtcl_wrote_them(renders):
    png, ppm_image = images.read(renders / "a.png"), images.read(renders / "a.ppm")
    assert (png.width, png.height, png.channels, png.maxval) == (24, 16, 3, 255)
    assert png.values == ppm.pixels(renders / "a.ppm")[1] == ppm_image.values
    pfm = images.read(renders / "a.pfm")
    assert (pfm.width, pfm.height, pfm.channels, pfm.maxval) == (24, 16, 3, None)
    # rtcl's 8-bit files hold the sRGB encoding of the PFM's linear floats: the
    # first row of the PFM (stored last) is the image's top row, as in the PNG.
    encoded = [round(255 * (12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055))
               for v in (min(max(v, 0.0), 1.0) for v in pfm.values[:72])]
    assert max(abs(a - b) for a, b in zip(encoded, png.values[:72])) <= 1


def test_same_pixels_in_another_format_or_kernel(renders):
    result = imgdiff(renders / "a.png", renders / "naive.png", renders / "a.ppm")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines == [f"{renders / 'naive.png'}: same pixels as {renders / 'a.png'}",
                     f"{renders / 'a.ppm'}: same pixels as {renders / 'a.png'}"]


def test_differences_are_counted_with_psnr_and_threshold(renders):
    reference, shallow = images.read(renders / "a.png"), images.read(renders / "shallow.png")
    pairs = [(a, b) for a, b in zip(reference.values, shallow.values) if a != b]
    largest = max(abs(a - b) for a, b in pairs)
    mse = sum((a - b) ** 2 for a, b in pairs) / len(reference.values) / 255 ** 2
    result = imgdiff(renders / "a.png", renders / "shallow.png")
    assert result.returncode == 0, result.stderr
    assert f"{len(pairs)} values differ (max {largest}/255)" in result.stdout
    assert f"PSNR {10 * math.log10(1 / mse):.2f} dB" in result.stdout
    failing = imgdiff(renders / "a.png", renders / "shallow.png", "--threshold", "1/255")
    assert failing.returncode == 1 and "FAIL (above threshold 0.00392157)" in failing.stdout
    passing = imgdiff(renders / "a.png", renders / "shallow.png", "-t", "1")
    assert passing.returncode == 0 and "; pass (threshold 1)" in passing.stdout


def test_pfm_differences_are_on_the_float_scale(renders):
    result = imgdiff(renders / "a.pfm", renders / "shallow.pfm")
    assert result.returncode == 0, result.stderr
    line = result.stdout.strip()
    assert "values differ from" in line and "/255" not in line and "PSNR" in line


@pytest.mark.skipif(shutil.which("idiff") is None, reason="no OpenImageIO idiff")
def test_other_formats_go_through_idiff(renders, tmp_path):
    render(tmp_path / "a.exr")
    render(tmp_path / "shallow.exr", "--depth", "1")
    result = imgdiff(renders / "a.pfm", tmp_path / "a.exr", tmp_path / "shallow.exr")
    assert result.returncode == 0, result.stderr
    same, differs = result.stdout.splitlines()
    assert same.endswith(f"same pixels as {renders / 'a.pfm'}")
    assert "pixels differ from" in differs and "PSNR" in differs


@pytest.mark.parametrize("tool", ["imgdiff.py", "ppmdiff.py"])
def test_missing_or_unreadable_files_are_one_line_and_exit_2(tmp_path, tool):
    write_ppm(tmp_path / "a.ppm", b"x", [0] * 6)
    (tmp_path / "text.png").write_text("not an image\n")
    (tmp_path / "broken.png").write_bytes(images.PNG_SIGNATURE + b"\0\0\0\rIHDR")
    for other, fragment in (("missing.png", "cannot read: No such file or directory"),
                            ("broken.png", "not a readable PNG file")):
        result = imgdiff(tmp_path / "a.ppm", tmp_path / other, tool=tool)
        assert result.returncode == 2
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in result.stderr
        assert lines[0].startswith(f"{tool}: error: ")
    result = imgdiff(tmp_path / "missing.ppm", tmp_path / "a.ppm", tool=tool)
    assert result.returncode == 2 and "missing.ppm: cannot read" in result.stderr
