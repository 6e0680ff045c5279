"""tools/ppmdiff.py: pixel comparison of PPM files whose headers differ."""
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import ppm  # noqa: E402


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
