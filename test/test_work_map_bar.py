"""--work-map's picture is exactly the render's size; --work-map-bar FILE
writes its scale bar, labelled with the unit, as one more output (issue 12
item 4)."""
import os
import pathlib
import subprocess
import sys

import pytest

np = pytest.importorskip("numpy")

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import ppm  # noqa: E402


def rtcl(*args, cwd):
    return subprocess.run([RTCL, "-q", "-k", "naive", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


def image_size(path):
    """Width and height of a PPM, or of a PNG from its IHDR chunk."""
    data = path.read_bytes()
    if data.startswith(b"P6"):
        return ppm.pixels(path)[0]
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR", data[:16]
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def writes_png(tmp_path):
    result = rtcl("--size", "4x4", "-o", str(tmp_path / "probe.png"), cwd=tmp_path)
    return result.returncode == 0


@pytest.mark.parametrize("size, extension", [
    ((40, 30), "ppm"), ((7, 93), "ppm"), ((130, 1), "ppm"), ((64, 48), "png"),
    ((333, 20), "png")])
def test_the_picture_is_the_render_size(tmp_path, size, extension):
    if extension == "png" and not writes_png(tmp_path):
        pytest.skip("a build without OpenImageIO")
    result = rtcl("--size", "%dx%d" % size, "-o", "x.ppm", "--work-map", "map." + extension,
                  cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert image_size(tmp_path / ("map." + extension)) == size
    assert image_size(tmp_path / "x.ppm") == size


def bar_pixels(path):
    (width, height), data = ppm.pixels(path)
    return np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)


@pytest.mark.parametrize("width, expected", [
    (40, (170, 40)), (300, (300, 40)), (900, (900, 80))])
def test_the_bar_has_its_own_file(tmp_path, width, expected):
    result = rtcl("--size", "%dx8" % width, "-o", "x.ppm", "--work-map", "map.ppm",
                  "--work-map-bar", "bar.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert image_size(tmp_path / "map.ppm") == (width, 8)
    assert image_size(tmp_path / "bar.ppm") == expected
    assert b"flops per pixel, 0 (dark) to " in (tmp_path / "bar.ppm").read_bytes()[:200]


def ink_rows(pixels):
    """The rows holding white (label) pixels."""
    return np.flatnonzero((pixels == 255).all(axis=2).any(axis=1))


def test_the_bar_carries_labels_and_the_unit(tmp_path):
    for scale in ["linear", "log"]:
        result = rtcl("--size", "300x20", "-o", "x.ppm", "--work-map", "map.ppm",
                      "--work-map-scale", scale, "--work-map-bar", scale + ".ppm", cwd=tmp_path)
        assert result.returncode == 0, result.stderr
    linear, log = bar_pixels(tmp_path / "linear.ppm"), bar_pixels(tmp_path / "log.ppm")
    rows = ink_rows(linear)
    # Ticks, then the labels' 7 rows, then the unit's 7 rows (40 rows at 1x:
    # strip 4-13, ticks 14-16, labels 19-25, unit 29-35).
    assert list(rows) == list(range(14, 17)) + list(range(19, 26)) + list(range(29, 36))
    unit = (linear[29:36] == 255).all(axis=2)
    columns = np.flatnonzero(unit.any(axis=0))
    # "flops per pixel, linear scale": 29 glyphs, centred.
    assert 20 < columns[0] and abs((columns[0] + columns[-1]) / 2 - 150) < 3
    assert columns[-1] - columns[0] > 120
    # The labels name the same counts on both; the unit line names the scale.
    assert not np.array_equal(linear[29:36], log[29:36])
    assert np.array_equal(linear[19:26, :40], log[19:26, :40])  # the "0" label


@pytest.mark.parametrize("options, message", [
    (["--work-map-bar", "bar.ppm"], "--work-map-bar: the bar is the legend of a --work-map "
     "picture"),
    (["--work-map", "map.npy", "--work-map-bar", "bar.ppm"], "give --work-map an image file"),
])
def test_a_bar_needs_a_picture(tmp_path, options, message):
    result = rtcl("--size", "8x8", "-o", "x.ppm", *options, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rtcl: ") and message in lines[0], lines
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("bar", ["x.ppm", "map.ppm", "./s.json", "link/map.ppm"])
def test_the_bar_names_a_file_of_its_own(tmp_path, bar):
    (tmp_path / "link").symlink_to(".")
    result = rtcl("--size", "8x8", "-o", "x.ppm", "--work-map", "map.ppm", "--stats", "s.json",
                  "--work-map-bar", bar, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert "--work-map-bar %s" % bar in result.stderr
    assert "name the same file: give each output a file of its own" in result.stderr
    assert os.listdir(tmp_path) == ["link"]


def test_an_unwritable_bar_leaves_no_files(tmp_path):
    result = rtcl("--size", "8x8", "-o", "x.ppm", "--work-map", "map.ppm",
                  "--work-map-bar", "no/such/dir/bar.ppm", cwd=tmp_path)
    assert result.returncode == 1, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and "no/such/dir/bar.ppm" in lines[0], result.stderr
    assert os.listdir(tmp_path) == []


def test_a_bar_format_that_cannot_be_written_leaves_no_files(tmp_path):
    result = rtcl("--size", "8x8", "-o", "x.ppm", "--work-map", "map.ppm",
                  "--work-map-bar", "bar.unknown-format", cwd=tmp_path)
    assert result.returncode != 0
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert "bar.unknown-format" in result.stderr
    assert os.listdir(tmp_path) == []


def test_the_help_says_the_bar_is_a_file_of_its_own():
    """Issue 44: --work-map's help promised "a picture with a colour scale bar",
    which --work-map-bar writes to another file."""
    text = subprocess.run([RTCL, "--help"], capture_output=True, text=True,
                          timeout=60).stdout
    entry = text.split("  --work-map FILE", 1)[1].split("\n      --work-map-scale", 1)[0]
    assert "with a colour scale bar" not in entry
    assert "bar --work-map-bar writes to a file of its own" in " ".join(entry.split())
    bar = text.split("  --work-map-bar FILE", 1)[1].split("\n      --schedule-map", 1)[0]
    assert "needs --work-map with a picture" in " ".join(bar.split())
