"""The measured SIMD efficiency at its two ends (docs/RENDERING.md, "SIMD
efficiency, measured"): the serial kernel, one lane of 32, is 1/32 in every
phase; a scene in which every pixel is one miss, with full warps, is 100 %; and
the model's error against it is reported.

Needs an NVIDIA OpenCL device that lets software see its warps (compute
capability 7.0 or more); skipped elsewhere, which is every CI machine. On a GPU
machine: `RTCL=path/to/rtcl python3 -m pytest test/test_simd_measured.py`, or
without pytest `RTCL=... python3 test/test_simd_measured.py` (GPU batch 39 ran it
so on the H100).
"""
import json
import os
import pathlib
import re
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
EMPTY = str(ROOT / "scenes" / "empty.json")
BOX = str(ROOT / "test" / "scenes" / "path_box.json")


def nvidia_platform():
    """Returns the index of the NVIDIA platform rtcl lists, or None."""
    listing = subprocess.run([RTCL, "--list-devices"], capture_output=True, text=True,
                             timeout=120).stdout
    match = re.search(r"^Platform #(\d+): .*NVIDIA", listing, re.MULTILINE)
    return match.group(1) if match else None


def counted(platform, *args):
    """Runs one counting render with a schedule map; returns (its --stats, its
    summary)."""
    with tempfile.TemporaryDirectory() as folder:
        folder = pathlib.Path(folder)
        result = subprocess.run([RTCL, "-p", platform, "-d", "0", *args, "-o",
                                 str(folder / "x.ppm"), "--flops", str(folder / "f.npy"),
                                 "--schedule-map", str(folder / "s.npy"), "--stats",
                                 str(folder / "stats.json")],
                                capture_output=True, text=True, timeout=600)
        assert result.returncode == 0, result.stderr
        return json.loads((folder / "stats.json").read_text()), result.stdout


def measured(platform, *args):
    """Runs one counting render and returns its simd_efficiency_measured."""
    return counted(platform, *args)[0]["simd_efficiency_measured"]


def check_serial_is_one_lane_of_32(platform):
    value = measured(platform, "-k", "serial", "--accel", "bvh", "--size", "64x48")
    assert value == {"intersect": 1 / 32, "traversal": 1 / 32, "both": 1 / 32}, value


def check_a_scene_of_misses_keeps_every_lane_busy(platform):
    # 64x48 pixels in 8x8 work-groups: full warps of 32, each pixel one miss.
    value = measured(platform, "-k", "naive", "-s", EMPTY, "--size", "64x48", "-w", "8x8")
    assert value["intersect"] == 1.0, value


def check_the_model_reports_its_error(platform):
    stats, summary = counted(platform, "-k", "dynamic", "--accel", "bvh", "--size", "96x64")
    both = stats["simd_efficiency_measured"]["both"]
    error = stats["simd_efficiency_model"] - both
    assert abs(stats["simd_model_error"] - error) < 1e-9, stats
    assert f"{100 * both:.1f}% in both" in summary, summary
    assert f"; {100 * error:+.1f} points from the measured)" in summary, summary


def check_paths_measure_the_shading_phase(platform):
    """Under the path integrator a third phase, the BSDF samples: one lane of
    32 in the serial kernel; in a single-pass kernel a share in (0, 1], and
    all three phases together reported beside both."""
    value = measured(platform, "-k", "serial", BOX, "--size", "16x8", "--spp", "2")
    assert value["shade"] == 1 / 32 and value["all"] == 1 / 32, value
    stats, summary = counted(platform, "-k", "dynamic", BOX, "--size", "64x32", "--spp", "4")
    value = stats["simd_efficiency_measured"]
    assert 0 < value["shade"] <= 1 and 0 < value["all"] <= 1, value
    assert f"{100 * value['shade']:.1f}% in shading steps" in summary, summary
    assert f"{100 * value['all']:.1f}% in all three" in summary, summary


CHECKS = (check_serial_is_one_lane_of_32, check_a_scene_of_misses_keeps_every_lane_busy,
          check_the_model_reports_its_error, check_paths_measure_the_shading_phase)

try:
    import pytest
except ImportError:      # run as a script on a GPU machine without pytest
    pytest = None

if pytest is not None:
    @pytest.fixture(scope="module")
    def platform():
        found = nvidia_platform()
        if found is None:
            pytest.skip("needs an NVIDIA OpenCL device (SIMD efficiency is measured "
                        "only there)")
        return found

    def test_serial_is_one_lane_of_32(platform):
        check_serial_is_one_lane_of_32(platform)

    def test_a_scene_of_misses_keeps_every_lane_busy(platform):
        check_a_scene_of_misses_keeps_every_lane_busy(platform)

    def test_the_model_reports_its_error(platform):
        check_the_model_reports_its_error(platform)

    def test_paths_measure_the_shading_phase(platform):
        check_paths_measure_the_shading_phase(platform)


if __name__ == "__main__":
    found = nvidia_platform()
    if found is None:
        sys.exit("no NVIDIA OpenCL platform: nothing to check")
    for check in CHECKS:
        check(found)
        print(f"passed: {check.__name__}")
