"""--work-map FILE.npy and float formats: the per-pixel flop counts
themselves, the same for every kernel (issue 12 item 4, first part)."""
import json
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
SIZE = ["--size", "40x30"]
KERNELS = ["serial", "naive", "cyclic", "dynamic", "persistent", "wavefront"]


def counts(tmp_path, kernel, name="map.npy", *extra):
    result = subprocess.run([RTCL, *SIZE, "-q", "-k", kernel, "-o", "x.ppm", "--work-map", name,
                             "--stats", "s.json", *extra], capture_output=True, text=True,
                            cwd=tmp_path, timeout=300)
    assert result.returncode == 0, result.stderr
    return tmp_path / name, json.loads((tmp_path / "s.json").read_text())


def test_npy_holds_every_pixels_count(tmp_path):
    path, stats = counts(tmp_path, "dynamic")
    array = np.load(path)
    assert array.dtype == np.uint64 and array.shape == (30, 40)
    assert int(array.sum()) == stats["total_flops"]
    assert array.min() > 0  # every pixel traces at least its primary ray


def test_the_counts_are_the_same_for_every_kernel(tmp_path):
    first = None
    for kernel in KERNELS:
        folder = tmp_path / kernel
        folder.mkdir()
        array = np.load(counts(folder, kernel)[0])
        if first is None:
            first = array
        assert np.array_equal(array, first), kernel


def test_a_float_image_holds_the_counts(tmp_path):
    npy, _ = counts(tmp_path, "naive")
    pfm, _ = counts(tmp_path, "naive", "map.pfm")
    data = pfm.read_bytes()
    header = data.split(b"\n", 3)
    assert header[0] == b"PF" and header[1] == b"40 30"
    values = np.frombuffer(header[3], dtype="<f4").reshape(30, 40, 3)[::-1]
    expected = np.load(npy).astype(np.float32)
    for channel in range(3):
        assert np.array_equal(values[:, :, channel], expected)


def test_a_picture_is_still_a_picture(tmp_path):
    path, _ = counts(tmp_path, "naive", "map.ppm")
    assert path.read_bytes().startswith(b"P6")


def luminance_of_map(path, height):
    """Mean luma of a PPM work map (the first `height` rows: all of it),
    and the file's first bytes (its header)."""
    (width, _), data = ppm.pixels(path)
    pixels = np.frombuffer(data, dtype=np.uint8).reshape(-1, width, 3)[:height]
    return float((pixels @ np.array([0.2126, 0.7152, 0.0722])).mean()), path.read_bytes()[:300]


def test_the_log_scale_lifts_the_cheap_pixels(tmp_path):
    linear, _ = counts(tmp_path, "naive", "linear.ppm")
    log, _ = counts(tmp_path, "naive", "log.ppm", "--work-map-scale", "log")
    linear_luma, linear_header = luminance_of_map(linear, 30)
    log_luma, log_header = luminance_of_map(log, 30)
    assert b"viridis, linear scale" in linear_header and b"viridis, log scale" in log_header
    # viridis brightens along the scale; most pixels cost far less than the
    # dearest, so the log scale moves them up.
    assert log_luma > linear_luma + 10
