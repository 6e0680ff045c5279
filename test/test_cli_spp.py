"""--spp and image.samples end to end (issue 12 item 1): the range and its
messages, the scene's value and the option overriding it, one sample being the
image of old, every kernel's antialiased image byte-identical, passes, and the
progress line only on a terminal."""
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import ppm  # noqa: E402

import terminal  # noqa: E402

RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SMALL = ["--size", "24x16"]


def rtcl(*args, **kwargs):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=ROOT, timeout=300,
                          **kwargs)


def expect_failure(result, status, message, directory):
    assert result.returncode == status, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert message in lines[0], lines[0]
    assert sorted(os.listdir(directory)) == [], "a failed run left files behind"


@pytest.mark.parametrize("value", ["0", "65537", "-1", "four", "2.5", ""])
def test_spp_out_of_range_is_a_usage_error(value, tmp_path):
    result = rtcl("--spp", value, "-o", str(tmp_path / "x.ppm"))
    expect_failure(result, 2,
                   f'rtcl: --spp: expected an integer between 1 and 65536, got "{value}"',
                   tmp_path)


def scene_with_image(tmp_path, image):
    with open(ROOT / "scenes" / "two_balls.json") as f:
        doc = json.load(f)
    doc["image"] = image
    path = tmp_path / "scene" / "t.json"
    path.parent.mkdir()
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("samples, message", [
    (0, "image.samples: must be between 1 and 65536, got 0"),
    (65537, "image.samples: must be between 1 and 65536, got 65537"),
    (2.5, "image.samples: must be an integer, got 2.5"),
    ("4", "image.samples: must be an integer, got a string"),
])
def test_bad_image_samples_are_refused(samples, message, tmp_path):
    scene = scene_with_image(tmp_path, {"width": 8, "height": 6, "samples": samples})
    out = tmp_path / "out"
    out.mkdir()
    result = rtcl("-s", str(scene), "-o", str(out / "x.ppm"))
    expect_failure(result, 1, f"{scene}: {message}", out)


def stats_of(tmp_path, *args):
    out, stats = tmp_path / "img.ppm", tmp_path / "stats.json"
    result = rtcl(*args, "-o", str(out), "--stats", str(stats))
    assert result.returncode == 0, result.stderr
    return json.loads(stats.read_text()), ppm.pixels(out)


def test_scene_samples_are_used_and_spp_overrides_them(tmp_path):
    scene = scene_with_image(tmp_path, {"width": 24, "height": 16, "samples": 3})
    stats, from_scene = stats_of(tmp_path, "-s", str(scene))
    assert stats["samples"] == 3
    stats, overridden = stats_of(tmp_path, "-s", str(scene), "--spp", "5")
    assert stats["samples"] == 5
    _, five = stats_of(tmp_path, "-s", "scenes/two_balls.json", *SMALL, "--spp", "5")
    assert overridden == five
    assert from_scene != five


def test_one_sample_is_the_default_image_and_more_change_it(tmp_path):
    stats, default = stats_of(tmp_path, *SMALL)
    assert (stats["samples"], stats["passes"]) == (1, 1)
    _, one = stats_of(tmp_path, *SMALL, "--spp", "1")
    _, four = stats_of(tmp_path, *SMALL, "--spp", "4")
    assert one == default
    assert four != default


@pytest.mark.slow
def test_every_kernel_gives_the_same_antialiased_image(tmp_path):
    _, want = stats_of(tmp_path, *SMALL, "-k", "serial", "--spp", "4")
    for kernel in ["naive", "cyclic", "dynamic", "persistent", "reference", "wavefront"]:
        _, got = stats_of(tmp_path, *SMALL, "-k", kernel, "--spp", "4")
        count, largest = ppm.differences(want[1], got[1])
        if kernel == "reference":  # double precision: near, not equal
            assert largest <= 16 and count <= 0.01 * len(want[1]), (count, largest)
        else:
            assert count == 0, (kernel, count, largest)


# 64x64 pixels at 2048 samples: two passes of about 4 million samples, and on the
# empty scene (every ray misses) quick even on a CPU.
PASSES = ["-s", "scenes/empty.json", "--size", "64x64", "--spp", "2048"]


def test_long_render_runs_in_passes_without_progress_off_a_terminal(tmp_path):
    result = rtcl(*PASSES, "-o", str(tmp_path / "x.ppm"), "--stats", str(tmp_path / "s.json"))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert json.loads((tmp_path / "s.json").read_text())["passes"] == 2
    assert "samples: 2048 per pixel in 2 passes" in result.stdout


def test_progress_shows_the_share_done_on_a_terminal(tmp_path):
    result, shown = terminal.on_terminal([RTCL, *PASSES, "-o", str(tmp_path / "x.ppm")], ROOT,
                                         timeout=300)
    assert result.returncode == 0
    # Two passes; the share moves within each (test_progress.py).
    assert re.search(rb"rendering \(dynamic\): [1-9]\d?% done", shown), shown
